//! Images, their views, and samplers: render-target attachments, colour-map textures, and
//! readback of rendered pixels. Uploads and readbacks go through staging buffers.

use std::sync::Arc;

use ash::vk;

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

    fn aspect(&self) -> vk::ImageAspectFlags {
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
        Ok(Self { _device: shared, life, raw, view, desc, name: name.to_string() })
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

    /// Records a layout transition with a full barrier between the given stages.
    pub fn record_transition(
        &self,
        rec: &mut Recorder<'_>,
        from: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
        to: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
    ) {
        rec.keep(self);
        // SAFETY: recording on this device; the image is live and kept by the recording.
        unsafe { record_image_barrier(rec, self.raw, self.desc.aspect(), from, to) };
    }

    /// Uploads tightly packed texels and leaves the image in `SHADER_READ_ONLY_OPTIMAL`,
    /// visible to fragment and compute shaders.
    pub fn upload(&self, gpu: &Gpu, texels: &[u8]) -> GpuResult<()> {
        let expected = texel_bytes(self.desc.format)
            .map(|b| b * u64::from(self.desc.width) * u64::from(self.desc.height));
        assert_eq!(Some(texels.len() as u64), expected, "texel data size for image `{}`", self.name);
        let staging = Buffer::<u8>::new(
            gpu,
            &format!("{} (staging)", self.name),
            texels.len() as u64,
            vk::BufferUsageFlags::empty(),
            MemoryKind::CpuToGpu,
        )?;
        let mut staging = staging;
        staging.mapped_mut()?.copy_from_slice(texels);
        gpu.run(|rec| {
            self.record_transition(
                rec,
                (vk::ImageLayout::UNDEFINED, vk::PipelineStageFlags::TOP_OF_PIPE, vk::AccessFlags::empty()),
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
            );
            let region = self.copy_region();
            rec.keep(&staging);
            // SAFETY: staging holds exactly the image's texels and is kept by the recording;
            // the image is in TRANSFER_DST.
            unsafe {
                rec.device().cmd_copy_buffer_to_image(
                    rec.raw(),
                    staging.raw(),
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            self.record_transition(
                rec,
                (
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_WRITE,
                ),
                (
                    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    vk::PipelineStageFlags::FRAGMENT_SHADER | vk::PipelineStageFlags::COMPUTE_SHADER,
                    vk::AccessFlags::SHADER_READ,
                ),
            );
        })
    }

    /// Records a copy of the whole image (which must be in `TRANSFER_SRC_OPTIMAL`) into `dst`,
    /// tightly packed. Panics if `dst` is smaller than the image's texels.
    pub fn record_copy_to_buffer<T: bytemuck::Pod>(&self, rec: &mut Recorder<'_>, dst: &Buffer<T>) {
        let needed = texel_bytes(self.desc.format)
            .map_or(0, |b| b * u64::from(self.desc.width) * u64::from(self.desc.height));
        assert!(dst.size_bytes() >= needed, "`{}` cannot hold image `{}`", dst.name(), self.name);
        rec.keep(self);
        rec.keep(dst);
        let region = self.copy_region();
        // SAFETY: recording on this device; both objects are kept by the recording, the
        // image's layout is the caller's documented precondition (a validation error, not
        // memory unsafety, if wrong) and `dst` holds the texels (checked above).
        unsafe {
            rec.device().cmd_copy_image_to_buffer(
                rec.raw(),
                self.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                dst.raw(),
                &[region],
            )
        };
    }

    /// The single full-image buffer/image copy region.
    fn copy_region(&self) -> vk::BufferImageCopy {
        full_copy_region(
            self.desc.aspect(),
            vk::Extent2D { width: self.desc.width, height: self.desc.height },
        )
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

/// Records an image memory barrier with a layout transition (also used on images the engine
/// does not own, such as a host's or a swapchain's).
///
/// # Safety
/// `image` is a live image of the recorder's device with `aspect`, one mip level and one
/// layer, and stays alive until the recording's work has finished.
pub unsafe fn record_image_barrier(
    rec: &mut Recorder<'_>,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    from: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
    to: (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(from.0)
        .new_layout(to.0)
        .src_access_mask(from.2)
        .dst_access_mask(to.2)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(subresource(aspect));
    // SAFETY: recording on this device; `image` per this function's contract.
    unsafe {
        rec.device().cmd_pipeline_barrier(
            rec.raw(),
            from.1,
            to.1,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            &[barrier],
        )
    };
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
