//! Offscreen render targets: a colour attachment (8-bit RGBA for pictures, 32-bit float RGBA
//! for values), a depth attachment, the render pass and framebuffer, and readback.

use ash::vk;

use super::draw_target::DrawTarget;

use crate::gpu::{
    Attachment, Buffer, ForeignImage, ForeignView, Framebuffer, Gpu, GpuResult, Image, ImageDesc,
    ImageResource, MemoryKind, Recorder, RenderPass,
};

/// Colour formats of a render target.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum ColorFormat {
    /// `R8G8B8A8_UNORM`: colour-mapped pictures (written to PNG as sRGB values).
    Rgba8,
    /// `R32G32B32A32_SFLOAT`: raw values (written to EXR).
    Rgba32F,
}

impl ColorFormat {
    /// The Vulkan format.
    pub fn vk(self) -> vk::Format {
        match self {
            Self::Rgba8 => vk::Format::R8G8B8A8_UNORM,
            Self::Rgba32F => vk::Format::R32G32B32A32_SFLOAT,
        }
    }

    /// What a colour attachment of `format` holds, if galerkin's pipelines write it:
    /// 8-bit UNORM RGBA or BGRA hold colours, 32-bit float RGBA raw values.
    pub fn of_attachment(format: vk::Format) -> Option<Self> {
        if !crate::gpu::is_drawable_color_format(format) {
            return None;
        }
        Some(if format == vk::Format::R32G32B32A32_SFLOAT { Self::Rgba32F } else { Self::Rgba8 })
    }

    fn texel_bytes(self) -> u64 {
        match self {
            Self::Rgba8 => 4,
            Self::Rgba32F => 16,
        }
    }
}

/// Read-back pixels, row-major from the top row.
#[derive(Clone, Debug, PartialEq)]
pub enum Pixels {
    /// 4 bytes per pixel.
    Rgba8(Vec<u8>),
    /// 4 floats per pixel.
    Rgba32F(Vec<f32>),
}

enum ColorAttachment {
    Owned(Image),
    Foreign { image: ForeignImage, view: ForeignView },
}

impl ColorAttachment {
    fn image(&self) -> &dyn ImageResource {
        match self {
            Self::Owned(i) => i,
            Self::Foreign { image, .. } => image,
        }
    }
}

/// Where a pass draws: colour (+ depth) attachments with their render pass and framebuffer.
pub struct RenderTarget {
    color: ColorAttachment,
    _depth: Image,
    framebuffer: Framebuffer,
    pass: RenderPass,
    format: ColorFormat,
    extent: vk::Extent2D,
}

/// Depth format every Vulkan implementation supports as an attachment.
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

impl RenderTarget {
    /// An offscreen target of `width`×`height` with a depth attachment.
    pub fn new(gpu: &Gpu, name: &str, width: u32, height: u32, format: ColorFormat) -> GpuResult<Self> {
        let desc = ImageDesc::color_target(width, height, format.vk());
        let color = Image::new(gpu, &format!("{name} colour"), desc)?;
        Self::around(gpu, name, ColorAttachment::Owned(color), format, width, height)
    }

    /// A target drawing into a host's colour image (the engine adds its own depth attachment,
    /// view and framebuffer, and destroys only those).
    ///
    /// # Safety
    /// `image` is a live 2D image of `gpu`'s device with `format`, `width`×`height`, one level
    /// and one layer, created with `COLOR_ATTACHMENT` usage (and `TRANSFER_SRC` for readback),
    /// and it outlives the target. It is cleared at the start of each pass (its prior contents
    /// and layout are discarded) and left in `TRANSFER_SRC_OPTIMAL`.
    pub unsafe fn from_host_image(
        gpu: &Gpu,
        name: &str,
        image: vk::Image,
        format: ColorFormat,
        width: u32,
        height: u32,
    ) -> GpuResult<Self> {
        // SAFETY: forwarded from this function's contract.
        let view = unsafe { ForeignView::new(gpu, image, format.vk()) }?;
        let extent = vk::Extent2D { width, height };
        // SAFETY: as above; its prior contents are discarded by the pass (UNDEFINED).
        let image = unsafe { ForeignImage::new(image, format.vk(), extent, vk::ImageLayout::UNDEFINED) };
        let color = ColorAttachment::Foreign { image, view };
        Self::around(gpu, name, color, format, width, height)
    }

    /// The depth attachment, render pass and framebuffer around a colour attachment.
    fn around(
        gpu: &Gpu,
        name: &str,
        color: ColorAttachment,
        format: ColorFormat,
        width: u32,
        height: u32,
    ) -> GpuResult<Self> {
        let desc = ImageDesc::depth_target(width, height, DEPTH_FORMAT);
        let depth = Image::new(gpu, &format!("{name} depth"), desc)?;
        let pass = RenderPass::new(gpu, format.vk(), Some(DEPTH_FORMAT))?;
        let extent = vk::Extent2D { width, height };
        let color_view: &dyn Attachment = match &color {
            ColorAttachment::Owned(image) => image,
            ColorAttachment::Foreign { view, .. } => view,
        };
        let framebuffer = Framebuffer::new(gpu, &pass, &[color_view, &depth], extent)?;
        Ok(Self { color, _depth: depth, framebuffer, pass, format, extent })
    }

    /// The whole target as the place a draw lands (between [`Self::record_begin`] and
    /// [`Self::record_end`]).
    pub fn draw_target(&self) -> DrawTarget<'_> {
        DrawTarget::new(&self.pass, self.extent.into())
            .unwrap_or_else(|e| unreachable!("an engine target is always drawable: {e}"))
    }

    /// The render pass pipelines drawing here are built against.
    pub fn render_pass(&self) -> &RenderPass {
        &self.pass
    }

    /// Size in pixels.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }

    /// Width / height.
    pub fn aspect(&self) -> f64 {
        f64::from(self.extent.width) / f64::from(self.extent.height)
    }

    /// Colour format.
    pub fn format(&self) -> ColorFormat {
        self.format
    }

    /// The colour image (in `TRANSFER_SRC_OPTIMAL` after a pass), for the recorder's image
    /// operations ([`Recorder::blit`], [`Recorder::copy_image_to_buffer`]).
    pub fn color_image(&self) -> &dyn ImageResource {
        self.color.image()
    }

    /// Keeps every object of the target alive until `rec`'s work has finished.
    pub fn keep(&self, rec: &mut Recorder<'_>) {
        match &self.color {
            ColorAttachment::Owned(image) => rec.keep(image),
            ColorAttachment::Foreign { view, .. } => rec.keep(view),
        }
        rec.keep(&self._depth);
        rec.keep(&self.framebuffer);
        rec.keep(&self.pass);
    }

    /// Records the start of the render pass, clearing colour to `clear` and depth to 1.
    pub fn record_begin(&self, rec: &mut Recorder<'_>, clear: [f32; 4]) {
        self.pass.record_begin(rec, &self.framebuffer, clear);
    }

    /// Records the end of the render pass: the colour image is then in
    /// `TRANSFER_SRC_OPTIMAL`, its writes visible to transfers (the pass's external
    /// dependency).
    pub fn record_end(&self, rec: &mut Recorder<'_>) {
        self.pass.record_end(rec);
        rec.attachment_written(
            self.color.image(),
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            vk::PipelineStageFlags2::TRANSFER,
        );
    }

    /// Records a copy of the colour image (after a pass) into `dst`, tightly packed. Panics
    /// if `dst` is smaller than [`RenderTarget::readback_bytes`].
    pub fn record_readback<T: bytemuck::Pod>(&self, rec: &mut Recorder<'_>, dst: &Buffer<T>) {
        assert!(dst.size_bytes() >= self.readback_bytes(), "`{}` cannot hold the target", dst.name());
        if let ColorAttachment::Foreign { view, .. } = &self.color {
            rec.keep(view);
        }
        rec.copy_image_to_buffer(self.color.image(), dst);
        rec.access(dst, crate::gpu::Access::HOST_READ);
    }

    /// Bytes of one full readback.
    pub fn readback_bytes(&self) -> u64 {
        self.format.texel_bytes() * u64::from(self.extent.width) * u64::from(self.extent.height)
    }

    /// Reads the colour image back (run after a pass has drawn into it).
    pub fn readback(&self, gpu: &Gpu) -> GpuResult<Pixels> {
        self.render_inner(gpu, None)
    }

    /// Records the pass `draw` in this target, then the copy of its colour image to a staging
    /// buffer, in one submission; returns the pixels. The common offscreen case.
    pub fn render(
        &self,
        gpu: &Gpu,
        clear: [f32; 4],
        draw: impl FnOnce(&mut Recorder<'_>),
    ) -> GpuResult<Pixels> {
        self.render_inner(gpu, Some((clear, Box::new(draw))))
    }

    #[allow(clippy::type_complexity)]
    fn render_inner(
        &self,
        gpu: &Gpu,
        draw: Option<([f32; 4], Box<dyn FnOnce(&mut Recorder<'_>) + '_>)>,
    ) -> GpuResult<Pixels> {
        let staging = self.readback_staging(gpu)?;
        gpu.run(|rec| {
            if let Some((clear, draw)) = draw {
                self.record_begin(rec, clear);
                draw(rec);
                self.record_end(rec);
            }
            self.record_readback(rec, &staging);
        })?;
        self.read_staging(&staging)
    }

    /// A host-visible buffer for one readback.
    pub(crate) fn readback_staging(&self, gpu: &Gpu) -> GpuResult<Buffer<u8>> {
        Buffer::<u8>::new(
            gpu,
            "render target readback",
            self.readback_bytes(),
            vk::BufferUsageFlags::empty(),
            MemoryKind::GpuToCpu,
        )
    }

    /// The pixels of a finished readback into `staging`.
    pub(crate) fn read_staging(&self, staging: &Buffer<u8>) -> GpuResult<Pixels> {
        let bytes = staging.mapped().ok_or_else(|| crate::gpu::GpuError::NotMappable {
            name: staging.name().to_string(),
            reason: "readback staging is not host-visible",
        })?;
        Ok(match self.format {
            ColorFormat::Rgba8 => Pixels::Rgba8(bytes.to_vec()),
            ColorFormat::Rgba32F => Pixels::Rgba32F(bytemuck::pod_collect_to_vec(bytes)),
        })
    }
}
