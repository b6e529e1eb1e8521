//! Images, their views, and samplers: render-target attachments, colour-map textures, and
//! readback of rendered pixels. Uploads and readbacks go through staging buffers.

use std::sync::{Arc, Mutex};

use ash::vk;

use super::access::Key;

use super::access::Access;
use super::buffer::Buffer;
use super::context::{DeviceShared, Gpu};
use super::error::{vk_error, GpuError, GpuResult, VkContext};
use super::lifetime::{Lifetime, Tracked};
use super::memory::MemoryKind;
use super::recorder::Recorder;

/// What image to make.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub struct ImageDesc {
    /// Width in texels.
    pub width: u32,
    /// Height in texels (1 for a 1D image).
    pub height: u32,
    /// Texel format.
    pub format: vk::Format,
    /// How it is used (transfer usage is added).
    pub usage: vk::ImageUsageFlags,
    /// `TYPE_1D` or `TYPE_2D`.
    pub dim: vk::ImageType,
}

impl ImageDesc {
    /// A 2D colour render target that can be read back and blitted.
    pub fn color_target(width: u32, height: u32, format: vk::Format) -> Self {
        Self {
            width,
            height,
            format,
            usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            dim: vk::ImageType::TYPE_2D,
        }
    }

    /// A 2D depth attachment.
    pub fn depth_target(width: u32, height: u32, format: vk::Format) -> Self {
        Self {
            width,
            height,
            format,
            usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
            dim: vk::ImageType::TYPE_2D,
        }
    }

    /// A 1D texture sampled by shaders (colour maps).
    pub fn texture_1d(width: u32, format: vk::Format) -> Self {
        Self { width, height: 1, format, usage: vk::ImageUsageFlags::SAMPLED, dim: vk::ImageType::TYPE_1D }
    }

    /// The aspects of its format (colour, or depth and stencil).
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => {
                vk::ImageAspectFlags::DEPTH
            }
            vk::Format::D24_UNORM_S8_UINT
            | vk::Format::D32_SFLOAT_S8_UINT
            | vk::Format::D16_UNORM_S8_UINT => vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL,
            _ => vk::ImageAspectFlags::COLOR,
        }
    }
}

/// Bytes per texel of the formats galerkin reads and writes.
pub fn texel_bytes(format: vk::Format) -> Option<u64> {
    Some(match format {
        vk::Format::R8G8B8A8_UNORM
        | vk::Format::R8G8B8A8_SRGB
        | vk::Format::B8G8R8A8_UNORM
        | vk::Format::B8G8R8A8_SRGB => 4,
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => 4,
        vk::Format::R32G32B32A32_SFLOAT => 16,
        vk::Format::R16G16B16A16_SFLOAT => 8,
        _ => return None,
    })
}

/// An image with one mip level, one layer, and a view of all of it.
pub struct Image {
    // `life` first: fields drop in order, and the lifetime must end while the device is alive.
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::Image,
    view: vk::ImageView,
    desc: ImageDesc,
    name: String,
    /// The layout the last recorded command leaves it in.
    layout: Mutex<vk::ImageLayout>,
}

impl Tracked for Image {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl Image {
    /// Creates the image, its memory and its view. Sizes over `maxImageDimension2D` are an
    /// error naming the image.
    pub fn new(gpu: &Gpu, name: &str, desc: ImageDesc) -> GpuResult<Self> {
        let shared = gpu.shared.clone();
        let limit = shared.caps.max_image_dimension_2d;
        if desc.width == 0 || desc.height == 0 || desc.width.max(desc.height) > limit {
            return Err(GpuError::OverLimit {
                name: name.to_string(),
                requested: u64::from(desc.width.max(desc.height)),
                limit: u64::from(limit),
                limit_name: "maxImageDimension2D (and at least 1)",
                unit: "texels",
            });
        }
        let info = vk::ImageCreateInfo::default()
            .image_type(desc.dim)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage | vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info on this device.
        let raw = unsafe { shared.raw.create_image(&info, None) }.map_err(|e| match e {
            vk::Result::ERROR_FORMAT_NOT_SUPPORTED => {
                GpuError::Unsupported(format!("format {:?} for image `{name}`", desc.format))
            }
            e => GpuError::Vk { call: "vkCreateImage", result: e },
        })?;
        // SAFETY: `raw` is a live image of this device.
        let requirements = unsafe { shared.raw.get_image_memory_requirements(raw) };
        let allocation = match shared.allocate(name, requirements, MemoryKind::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: never used.
                unsafe { shared.raw.destroy_image(raw, None) };
                return Err(e);
            }
        };
        let bound = {
            // SAFETY: memory of an allowed type at its offset.
            unsafe { shared.raw.bind_image_memory(raw, allocation.memory(), allocation.offset()) }
        };
        let view_type = if desc.dim == vk::ImageType::TYPE_1D {
            vk::ImageViewType::TYPE_1D
        } else {
            vk::ImageViewType::TYPE_2D
        };
        let view = bound.and_then(|()| {
            let view_info = vk::ImageViewCreateInfo::default()
                .image(raw)
                .view_type(view_type)
                .format(desc.format)
                .subresource_range(subresource(desc.aspect()));
            // SAFETY: the image is bound to memory.
            unsafe { shared.raw.create_image_view(&view_info, None) }
        });
        let view = match view {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: never used.
                unsafe { shared.raw.destroy_image(raw, None) };
                shared.free(allocation);
                return Err(vk_error("vkCreateImageView", e));
            }
        };
        shared.set_name(raw, name);
        let life = Lifetime::new(&shared, name, move |dev| {
            // SAFETY: the last reference is gone: no recording or set uses the image.
            unsafe {
                dev.raw.destroy_image_view(view, None);
                dev.raw.destroy_image(raw, None);
            }
            dev.free(allocation);
        });
        Ok(Self {
            _device: shared,
            life,
            raw,
            view,
            desc,
            name: name.to_string(),
            layout: Mutex::new(vk::ImageLayout::UNDEFINED),
        })
    }

    /// The Vulkan image.
    pub fn raw(&self) -> vk::Image {
        self.raw
    }

    /// Its view.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }

    /// What it was made as.
    pub fn desc(&self) -> &ImageDesc {
        &self.desc
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Uploads tightly packed texels and leaves the image in `SHADER_READ_ONLY_OPTIMAL`.
    pub fn upload(&mut self, gpu: &Gpu, texels: &[u8]) -> GpuResult<()> {
        let expected = texel_bytes(self.desc.format)
            .map(|b| b * u64::from(self.desc.width) * u64::from(self.desc.height));
        assert_eq!(Some(texels.len() as u64), expected, "texel data size for image `{}`", self.name);
        let mut staging = Buffer::<u8>::new(
            gpu,
            &format!("{} (staging)", self.name),
            texels.len() as u64,
            vk::BufferUsageFlags::empty(),
            MemoryKind::CpuToGpu,
        )?;
        staging.mapped_mut()?.copy_from_slice(texels);
        let extent = self.extent();
        gpu.run(|rec| {
            rec.copy_buffer_to_image(&staging, self, vk::Offset2D::default(), extent);
            let readers = Access::COMPUTE_READ.and(Access::GRAPHICS_READ);
            rec.transition(self, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, readers);
        })
    }

    /// Records a copy of the whole image into `dst`, tightly packed (the recorder moves the
    /// image to `TRANSFER_SRC_OPTIMAL` if it is not there). Panics if `dst` is smaller than
    /// the image's texels.
    pub fn record_copy_to_buffer<T: bytemuck::Pod>(&self, rec: &mut Recorder<'_>, dst: &Buffer<T>) {
        rec.copy_image_to_buffer(self, dst);
    }

    /// Its extent.
    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.desc.width, height: self.desc.height }
    }
}

/// The copy of a whole single-level, single-layer image of `extent` to or from a tightly
/// packed buffer (also for images the engine does not own).
pub(crate) fn full_copy_region(aspect: vk::ImageAspectFlags, extent: vk::Extent2D) -> vk::BufferImageCopy {
    vk::BufferImageCopy {
        buffer_offset: 0,
        buffer_row_length: 0,
        buffer_image_height: 0,
        image_subresource: vk::ImageSubresourceLayers {
            aspect_mask: aspect,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        },
        image_offset: vk::Offset3D::default(),
        image_extent: vk::Extent3D { width: extent.width, height: extent.height, depth: 1 },
    }
}

/// The whole single-level, single-layer subresource.
pub(crate) fn subresource(aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: aspect,
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

/// A sampler.
pub struct Sampler {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::Sampler,
}

impl Tracked for Sampler {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl Sampler {
    /// A clamp-to-edge sampler with linear (or nearest) filtering and no mipmaps, as colour
    /// maps use.
    pub fn new(gpu: &Gpu, linear: bool) -> GpuResult<Self> {
        let filter = if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        // SAFETY: valid create info on this device.
        let raw = unsafe { gpu.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        let life = Lifetime::new(&gpu.shared, "a sampler", move |dev| {
            // SAFETY: no recording or set uses it any more.
            unsafe { dev.raw.destroy_sampler(raw, None) }
        });
        Ok(Self { _device: gpu.shared.clone(), life, raw })
    }

    /// The Vulkan handle.
    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }
}

/// An image a recorder can record transfers and layout changes of: an engine [`Image`], or
/// a [`ForeignImage`] (a host's or a swapchain's). The recorder tracks its layout and derives
/// the barriers its commands need.
pub trait ImageResource {
    /// The Vulkan image.
    fn handle(&self) -> vk::Image;
    /// Its format.
    fn format(&self) -> vk::Format;
    /// Its extent (one mip level, one layer).
    fn extent(&self) -> vk::Extent2D;
    /// Its aspects.
    fn aspect(&self) -> vk::ImageAspectFlags;
    /// How the recorder tracks it (not for use outside the engine).
    #[doc(hidden)]
    fn tracking(&self) -> ImageTracking<'_>;
}

/// How a recorder tracks one image: its key, the lifetime a recording keeps (an engine
/// image's), and the layout its last recorded command leaves it in.
#[doc(hidden)]
pub struct ImageTracking<'a> {
    pub(crate) key: Key,
    pub(crate) life: Option<&'a Arc<Lifetime>>,
    pub(crate) layout: &'a Mutex<vk::ImageLayout>,
}

impl ImageResource for Image {
    fn handle(&self) -> vk::Image {
        self.raw
    }
    fn format(&self) -> vk::Format {
        self.desc.format
    }
    fn extent(&self) -> vk::Extent2D {
        Image::extent(self)
    }
    fn aspect(&self) -> vk::ImageAspectFlags {
        self.desc.aspect()
    }
    fn tracking(&self) -> ImageTracking<'_> {
        ImageTracking {
            key: Key::Object(Arc::as_ptr(&self.life) as usize),
            life: Some(&self.life),
            layout: &self.layout,
        }
    }
}

/// An image galerkin does not own — a swapchain's, or a host's — described so that a
/// [`Recorder`] can record safe, layout-tracked transfers and layout changes of it.
///
/// ```compile_fail,E0133
/// # use galerkin::gpu::{vk, ForeignImage};
/// # fn f(handle: vk::Image) {
/// // Wrapping a raw handle promises that it is alive and in the stated layout: `unsafe`.
/// let image = ForeignImage::new(handle, vk::Format::B8G8R8A8_UNORM, vk::Extent2D { width: 4, height: 4 }, vk::ImageLayout::UNDEFINED);
/// # }
/// ```
#[derive(Debug)]
pub struct ForeignImage {
    raw: vk::Image,
    format: vk::Format,
    extent: vk::Extent2D,
    layout: Mutex<vk::ImageLayout>,
}

impl ForeignImage {
    /// Describes `image`.
    ///
    /// # Safety
    /// `image` is a colour image of the recorder's device with one mip level and one layer, of
    /// `format` and `extent`, created with the transfer usages the recorded commands need; it
    /// is in `layout` when the first command recorded for it executes, and it stays alive until
    /// every recording that records it has finished.
    pub unsafe fn new(
        image: vk::Image,
        format: vk::Format,
        extent: vk::Extent2D,
        layout: vk::ImageLayout,
    ) -> Self {
        Self { raw: image, format, extent, layout: Mutex::new(layout) }
    }

    /// The layout its last recorded command leaves it in.
    pub fn layout(&self) -> vk::ImageLayout {
        *self.layout.lock().unwrap_or_else(|p| p.into_inner())
    }
}

impl ImageResource for ForeignImage {
    fn handle(&self) -> vk::Image {
        self.raw
    }
    fn format(&self) -> vk::Format {
        self.format
    }
    fn extent(&self) -> vk::Extent2D {
        self.extent
    }
    fn aspect(&self) -> vk::ImageAspectFlags {
        vk::ImageAspectFlags::COLOR
    }
    fn tracking(&self) -> ImageTracking<'_> {
        use ash::vk::Handle;
        ImageTracking { key: Key::Foreign(self.raw.as_raw()), life: None, layout: &self.layout }
    }
}
