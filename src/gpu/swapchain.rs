//! Window surfaces and swapchains (feature `viewer`). The engine never renders into swapchain
//! images directly: a frame renders offscreen with the same render pass as every other output
//! and is blitted to the acquired image, so what a window shows is what a PNG would hold.

use std::sync::Arc;

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};

/// The instance extensions a window on `display` needs (pass them in
/// [`super::GpuDesc::instance_extensions`]).
pub fn surface_extensions(display: RawDisplayHandle) -> GpuResult<Vec<&'static std::ffi::CStr>> {
    let names = ash_window::enumerate_required_extensions(display).vk("enumerate surface extensions")?;
    // SAFETY: ash-window returns pointers to static NUL-terminated extension names.
    Ok(names.iter().map(|&p| unsafe { std::ffi::CStr::from_ptr(p) }).collect())
}

/// A window surface.
pub struct Surface {
    /// Keeps the instance alive until the surface is destroyed.
    _shared: Arc<DeviceShared>,
    loader: ash::khr::surface::Instance,
    raw: vk::SurfaceKHR,
}

impl Surface {
    /// Creates a surface for a window and checks the engine's queue can present to it.
    ///
    /// # Safety
    /// The handles are valid and the window outlives the surface; the instance was created
    /// with [`surface_extensions`] of this display.
    pub unsafe fn new(gpu: &Gpu, display: RawDisplayHandle, window: RawWindowHandle) -> GpuResult<Self> {
        let shared = gpu.shared.clone();
        // SAFETY: forwarded from this function's contract.
        let raw =
            unsafe { ash_window::create_surface(&shared.entry, &shared.instance, display, window, None) }
                .vk("vkCreate*SurfaceKHR")?;
        let loader = ash::khr::surface::Instance::new(&shared.entry, &shared.instance);
        // SAFETY: the surface and physical device belong to this instance.
        let ok =
            unsafe { loader.get_physical_device_surface_support(shared.physical, shared.queue_family, raw) };
        if !matches!(ok, Ok(true)) {
            // SAFETY: nothing uses the new surface.
            unsafe { loader.destroy_surface(raw, None) };
            return Err(GpuError::Unsupported("presenting to this window from the engine's queue".into()));
        }
        Ok(Self { _shared: shared, loader, raw })
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: the swapchains made on this surface hold a borrow-free handle but are dropped
        // first by their owner (the viewer keeps them in that order).
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// A swapchain with its images, in a UNORM 8-bit format where the surface has one (so that
/// blitted colours are stored unchanged, as in PNG files).
pub struct Swapchain {
    shared: Arc<DeviceShared>,
    loader: ash::khr::swapchain::Device,
    raw: vk::SwapchainKHR,
    images: Vec<vk::Image>,
    format: vk::Format,
    extent: vk::Extent2D,
    readable: bool,
    /// Signalled when an acquired image is ready (one frame in flight).
    pub image_available: vk::Semaphore,
    /// Per image: signalled when the frame drawn into it may be presented.
    pub render_finished: Vec<vk::Semaphore>,
}

impl Swapchain {
    /// Creates a swapchain of (about) `width`×`height` for `surface`, replacing `old`.
    pub fn new(
        gpu: &Gpu,
        surface: &Surface,
        width: u32,
        height: u32,
        old: Option<&Swapchain>,
    ) -> GpuResult<Self> {
        let shared = gpu.shared.clone();
        let (sl, s, p) = (&surface.loader, surface.raw, shared.physical);
        // SAFETY: plain queries on objects of this instance.
        let caps = unsafe { sl.get_physical_device_surface_capabilities(p, s) }.vk("surface capabilities")?;
        // SAFETY: as above.
        let formats = unsafe { sl.get_physical_device_surface_formats(p, s) }.vk("surface formats")?;
        let format = formats
            .iter()
            .find(|f| matches!(f.format, vk::Format::B8G8R8A8_UNORM | vk::Format::R8G8B8A8_UNORM))
            .or_else(|| formats.first())
            .copied()
            .ok_or_else(|| GpuError::Unsupported("any format on this surface".into()))?;
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST;
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        if !caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_DST) {
            return Err(GpuError::Unsupported("blitting into swapchain images (TRANSFER_DST)".into()));
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(s)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(alpha)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old.map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = ash::khr::swapchain::Device::new(&shared.instance, &shared.raw);
        // SAFETY: valid create info; the device was created with VK_KHR_swapchain.
        let raw = unsafe { loader.create_swapchain(&info, None) }.vk("vkCreateSwapchainKHR")?;
        let mut me = Self {
            shared,
            loader,
            raw,
            images: Vec::new(),
            format: format.format,
            extent,
            readable,
            image_available: vk::Semaphore::null(),
            render_finished: Vec::new(),
        };
        // SAFETY: `raw` is a live swapchain of this device.
        me.images = unsafe { me.loader.get_swapchain_images(raw) }.vk("vkGetSwapchainImagesKHR")?;
        let semaphore = |d: &ash::Device| {
            // SAFETY: plain object creation.
            unsafe { d.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }.vk("vkCreateSemaphore")
        };
        me.image_available = semaphore(&me.shared.raw)?;
        for _ in 0..me.images.len() {
            let s = semaphore(&me.shared.raw)?;
            me.render_finished.push(s);
        }
        Ok(me)
    }

    /// Image size.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// Image format.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// True if images can be copied out (screenshots of what was presented).
    pub fn readable(&self) -> bool {
        self.readable
    }

    /// The images.
    pub fn images(&self) -> &[vk::Image] {
        &self.images
    }

    /// Acquires the next image, signalling [`Swapchain::image_available`]. `None` when the
    /// swapchain is out of date and must be recreated.
    pub fn acquire(&self) -> GpuResult<Option<u32>> {
        // SAFETY: one frame in flight: the previous wait on `image_available` has completed.
        match unsafe {
            self.loader.acquire_next_image(self.raw, u64::MAX, self.image_available, vk::Fence::null())
        } {
            Ok((i, _suboptimal)) => Ok(Some(i)),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(vk_error("vkAcquireNextImageKHR", e)),
        }
    }

    /// Presents image `index` after [`Swapchain::render_finished`]`[index]`. Returns false
    /// when the swapchain should be recreated.
    pub fn present(&self, index: u32) -> GpuResult<bool> {
        let waits = [self.render_finished[index as usize]];
        let chains = [self.raw];
        let indices = [index];
        let info =
            vk::PresentInfoKHR::default().wait_semaphores(&waits).swapchains(&chains).image_indices(&indices);
        let queue = self.shared.queue.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: the queue is externally synchronised by its mutex; the image was acquired.
        match unsafe { self.loader.queue_present(*queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(vk_error("vkQueuePresentKHR", e)),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: the owner waits for the last frame's fence before dropping; presentation
        // engine use of the images ends with the swapchain's destruction.
        unsafe {
            for s in self.render_finished.drain(..) {
                self.shared.raw.destroy_semaphore(s, None);
            }
            self.shared.raw.destroy_semaphore(self.image_available, None);
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
