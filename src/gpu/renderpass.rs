//! Render passes and framebuffers. galerkin's own passes draw into one colour attachment (plus
//! an optional depth attachment) cleared at the start and left in `TRANSFER_SRC_OPTIMAL` at the
//! end — ready to be read back, written to a file, or blitted to a window. The same render pass
//! serves the offscreen path, the viewer (which blits the result to its swapchain) and a host's
//! own image. A host's own render pass is described to the engine by
//! [`RenderPass::from_host`], and a host's dynamic rendering (`vkCmdBeginRendering`) by its
//! attachment formats with [`RenderPass::dynamic`]: galerkin's pipelines are then built for it
//! and draw inside it, begun, ended and owned by the host.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use ash::vk;

use super::context::{DeviceShared, Gpu};
use super::error::{GpuError, GpuResult, VkContext};
use super::image::Image;
use super::lifetime::{Lifetime, Tracked};
use super::recorder::Recorder;

/// A render pass galerkin's pipelines draw in: the engine's own (single subpass: colour
/// cleared, stored, ending in `TRANSFER_SRC_OPTIMAL`, and an optional depth attachment) or a
/// host's ([`RenderPass::from_host`]: the subpass galerkin draws in, with its colour and depth
/// formats).
pub struct RenderPass {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::RenderPass,
    color_format: vk::Format,
    depth_format: Option<vk::Format>,
    subpass: u32,
    /// `None` for the engine's own passes (all compatible when their formats agree); a unique
    /// number for each host pass (whose compatibility the engine cannot see).
    host_id: Option<u64>,
    /// True for a host's dynamic rendering (no render-pass object: `raw` is null).
    dynamic: bool,
}

/// What the engine must know of a host's render pass to draw in it (see
/// [`RenderPass::from_host`]).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct HostRenderPass {
    /// The render pass.
    pub raw: vk::RenderPass,
    /// The subpass galerkin's draws are recorded in.
    pub subpass: u32,
    /// Format of that subpass's one colour attachment.
    pub color_format: vk::Format,
    /// Format of its depth attachment, if it has one. The spectral and spacetime draws need
    /// one (they order surfaces and edges by depth) and refuse a pass without; simpler draws
    /// (the demo field) are then not depth-tested.
    pub depth_format: Option<vk::Format>,
}

/// Which pipelines can draw in a render pass: galerkin's own passes with equal formats are
/// compatible; each host pass is its own class. Capabilities key their pipeline caches by it.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum PassKey {
    /// An engine render pass with these colour and depth formats.
    Engine(vk::Format, Option<vk::Format>),
    /// The host render pass with this number.
    Host(u64),
    /// A host's dynamic rendering with these colour and depth formats (pipelines built with
    /// `VkPipelineRenderingCreateInfo`, compatible whenever the formats agree).
    Dynamic(vk::Format, Option<vk::Format>),
}

/// True for the colour formats galerkin's pipelines write: 8-bit UNORM RGBA or BGRA (colours,
/// sRGB-encoded by the shaders) and 32-bit float RGBA (raw values).
pub fn is_drawable_color_format(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::R8G8B8A8_UNORM | vk::Format::B8G8R8A8_UNORM | vk::Format::R32G32B32A32_SFLOAT
    )
}

/// Numbers host render passes.
static NEXT_HOST_PASS: AtomicU64 = AtomicU64::new(1);

impl RenderPass {
    /// Creates the render pass. Its external dependencies order earlier transfer reads of the
    /// attachment before this pass's writes, and its colour writes before later transfers.
    pub fn new(gpu: &Gpu, color_format: vk::Format, depth_format: Option<vk::Format>) -> GpuResult<Self> {
        let mut attachments = vec![vk::AttachmentDescription::default()
            .format(color_format)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
            .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)];
        if let Some(df) = depth_format {
            attachments.push(
                vk::AttachmentDescription::default()
                    .format(df)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
                    .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
                    .initial_layout(vk::ImageLayout::UNDEFINED)
                    .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
            );
        }
        let color_ref =
            [vk::AttachmentReference { attachment: 0, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
        let depth_ref = vk::AttachmentReference {
            attachment: 1,
            layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
        };
        let mut subpass = vk::SubpassDescription::default()
            .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
            .color_attachments(&color_ref);
        if depth_format.is_some() {
            subpass = subpass.depth_stencil_attachment(&depth_ref);
        }
        let fragment_tests =
            vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS;
        let dependencies = [
            vk::SubpassDependency {
                src_subpass: vk::SUBPASS_EXTERNAL,
                dst_subpass: 0,
                src_stage_mask: vk::PipelineStageFlags::TRANSFER
                    | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                    | fragment_tests,
                dst_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT | fragment_tests,
                src_access_mask: vk::AccessFlags::TRANSFER_WRITE
                    | vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
                dst_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE
                    | vk::AccessFlags::COLOR_ATTACHMENT_READ
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_READ
                    | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
                dependency_flags: vk::DependencyFlags::empty(),
            },
            vk::SubpassDependency {
                src_subpass: 0,
                dst_subpass: vk::SUBPASS_EXTERNAL,
                src_stage_mask: vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                dst_stage_mask: vk::PipelineStageFlags::TRANSFER,
                src_access_mask: vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                dst_access_mask: vk::AccessFlags::TRANSFER_READ,
                dependency_flags: vk::DependencyFlags::empty(),
            },
        ];
        let subpasses = [subpass];
        let info = vk::RenderPassCreateInfo::default()
            .attachments(&attachments)
            .subpasses(&subpasses)
            .dependencies(&dependencies);
        // SAFETY: valid create info on this device.
        let raw = unsafe { gpu.device().create_render_pass(&info, None) }.vk("vkCreateRenderPass")?;
        let life = Lifetime::new(&gpu.shared, "a render pass", move |dev| {
            // SAFETY: no framebuffer or recording uses it any more.
            unsafe { dev.raw.destroy_render_pass(raw, None) }
        });
        Ok(Self {
            life,
            _device: gpu.shared.clone(),
            raw,
            color_format,
            depth_format,
            subpass: 0,
            host_id: None,
            dynamic: false,
        })
    }

    /// Describes a host's dynamic rendering (`vkCmdBeginRendering`, Vulkan 1.3 or
    /// `VK_KHR_dynamic_rendering`) by the formats of its one colour attachment and its depth
    /// attachment, so that galerkin's pipelines are built for it (with
    /// `VkPipelineRenderingCreateInfo`) and record their draws between the host's
    /// `vkCmdBeginRendering` and `vkCmdEndRendering`. No Vulkan object is made; keep it, as
    /// pipelines are cached per format pair.
    ///
    /// [`GpuError::Unsupported`] if the device was not created with dynamic rendering enabled
    /// ([`super::Capabilities::dynamic_rendering`]) or the colour format is not one galerkin
    /// writes (`R8G8B8A8_UNORM`, `B8G8R8A8_UNORM`, `R32G32B32A32_SFLOAT`). The host's
    /// rendering must be single-sampled with exactly that one colour attachment (location 0)
    /// and a depth attachment of `depth_format` (none if `None`), without multiview.
    pub fn dynamic(gpu: &Gpu, color_format: vk::Format, depth_format: Option<vk::Format>) -> GpuResult<Self> {
        if !gpu.caps().dynamic_rendering {
            return Err(GpuError::Unsupported(
                "dynamic rendering (enable Vulkan 1.3's dynamicRendering or VK_KHR_dynamic_rendering \
                 on the device, and say so in RawDevice::dynamic_rendering)"
                    .into(),
            ));
        }
        if !is_drawable_color_format(color_format) {
            return Err(GpuError::Unsupported(format!(
                "drawing into a host colour attachment of format {color_format:?} (galerkin writes \
                 R8G8B8A8_UNORM, B8G8R8A8_UNORM or R32G32B32A32_SFLOAT)"
            )));
        }
        let life = Lifetime::new(&gpu.shared, "a host's dynamic rendering", |_| {
            // Nothing to destroy.
        });
        Ok(Self {
            life,
            _device: gpu.shared.clone(),
            raw: vk::RenderPass::null(),
            color_format,
            depth_format,
            subpass: 0,
            host_id: None,
            dynamic: true,
        })
    }

    /// Describes a host's render pass so that galerkin's pipelines can be built for it and
    /// record their draws inside it (the host begins and ends it; the engine destroys nothing
    /// of it). Make one per host render pass and keep it: pipelines are cached per description.
    ///
    /// The colour attachment must be one galerkin writes: `R8G8B8A8_UNORM` or
    /// `B8G8R8A8_UNORM` (colours, written sRGB-encoded, as into a PNG) or `R32G32B32A32_SFLOAT`
    /// (raw values); anything else, an `_SRGB` format included (it would encode the colours a
    /// second time), is [`GpuError::Unsupported`]. The subpass is single-sampled.
    ///
    /// # Safety
    /// - `desc.raw` is a live render pass of `gpu`'s device whose subpass `desc.subpass` has
    ///   exactly one colour attachment, of `desc.color_format`, single-sampled, and the depth
    ///   attachment `desc.depth_format` says (none if `None`);
    /// - it stays alive while pipelines are built for it (galerkin builds them on first draw
    ///   into it, and not later than that).
    pub unsafe fn from_host(gpu: &Gpu, desc: HostRenderPass) -> GpuResult<Self> {
        if !is_drawable_color_format(desc.color_format) {
            return Err(GpuError::Unsupported(format!(
                "drawing into a host colour attachment of format {:?} (galerkin writes R8G8B8A8_UNORM, \
                 B8G8R8A8_UNORM or R32G32B32A32_SFLOAT)",
                desc.color_format
            )));
        }
        let life = Lifetime::new(&gpu.shared, "a host's render pass", |_| {
            // The host owns and destroys it.
        });
        Ok(Self {
            life,
            _device: gpu.shared.clone(),
            raw: desc.raw,
            color_format: desc.color_format,
            depth_format: desc.depth_format,
            subpass: desc.subpass,
            host_id: Some(NEXT_HOST_PASS.fetch_add(1, Ordering::Relaxed)),
            dynamic: false,
        })
    }

    /// The pipeline compatibility class of this pass (see [`PassKey`]).
    pub fn key(&self) -> PassKey {
        match self.host_id {
            Some(id) => PassKey::Host(id),
            None if self.dynamic => PassKey::Dynamic(self.color_format, self.depth_format),
            None => PassKey::Engine(self.color_format, self.depth_format),
        }
    }

    /// The subpass galerkin draws in (0 for the engine's own passes).
    pub fn subpass(&self) -> u32 {
        self.subpass
    }

    /// True for a host's render pass or dynamic rendering (begun and ended by the host).
    pub fn is_host(&self) -> bool {
        self.host_id.is_some() || self.dynamic
    }

    /// True for a host's dynamic rendering ([`RenderPass::dynamic`]).
    pub fn is_dynamic(&self) -> bool {
        self.dynamic
    }

    /// The Vulkan handle (pipelines are built against it); null for dynamic rendering.
    pub fn raw(&self) -> vk::RenderPass {
        self.raw
    }

    /// Colour attachment format.
    pub fn color_format(&self) -> vk::Format {
        self.color_format
    }

    /// Depth attachment format, if any.
    pub fn depth_format(&self) -> Option<vk::Format> {
        self.depth_format
    }

    /// Records `vkCmdBeginRenderPass` on `framebuffer` clearing colour to `clear` and depth to
    /// 1 (outside a render pass; the pass and framebuffer are kept alive). Panics if the
    /// framebuffer was made for another render pass.
    pub fn record_begin(&self, rec: &mut Recorder<'_>, framebuffer: &Framebuffer, clear: [f32; 4]) {
        assert!(framebuffer.pass == self.raw, "the framebuffer was made for another render pass");
        assert!(!self.is_host(), "a host's render pass is begun by the host");
        rec.keep(self);
        rec.keep(framebuffer);
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: clear } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        ];
        let n = if self.depth_format.is_some() { 2 } else { 1 };
        let info = vk::RenderPassBeginInfo::default()
            .render_pass(self.raw)
            .framebuffer(framebuffer.raw)
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: framebuffer.extent })
            .clear_values(&clears[..n]);
        // The barriers declared for the draws (their reads of earlier writes) go before it.
        rec.flush();
        // SAFETY: recording on this device; the framebuffer matches this pass (checked) and
        // both are kept alive.
        unsafe { rec.device().cmd_begin_render_pass(rec.cmd(), &info, vk::SubpassContents::INLINE) };
    }

    /// Records `vkCmdEndRenderPass`.
    pub fn record_end(&self, rec: &mut Recorder<'_>) {
        assert!(!self.is_host(), "a host's render pass is ended by the host");
        // SAFETY: recording on this device, inside this render pass (the caller's documented
        // state; a validation error, not memory unsafety, otherwise).
        unsafe { rec.device().cmd_end_render_pass(rec.cmd()) };
    }
}

impl std::fmt::Debug for RenderPass {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RenderPass")
            .field("color_format", &self.color_format)
            .field("depth_format", &self.depth_format)
            .field("subpass", &self.subpass)
            .field("host", &self.is_host())
            .field("dynamic", &self.dynamic)
            .finish()
    }
}

impl Tracked for RenderPass {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

/// An image view a framebuffer can hold: an engine [`Image`] or a [`ForeignView`].
pub trait Attachment: Tracked {
    /// The view.
    fn view(&self) -> vk::ImageView;
}

impl Attachment for Image {
    fn view(&self) -> vk::ImageView {
        Image::view(self)
    }
}

impl Attachment for ForeignView {
    fn view(&self) -> vk::ImageView {
        self.raw
    }
}

/// A framebuffer of attachment views for a [`RenderPass`]; it keeps its attachments alive.
pub struct Framebuffer {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::Framebuffer,
    pass: vk::RenderPass,
    extent: vk::Extent2D,
}

impl Tracked for Framebuffer {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl Framebuffer {
    /// Creates a framebuffer; `attachments` are the colour view then the depth view (if the
    /// pass has one), each at least `extent`.
    pub fn new(
        gpu: &Gpu,
        pass: &RenderPass,
        attachments: &[&dyn Attachment],
        extent: vk::Extent2D,
    ) -> GpuResult<Self> {
        if pass.is_host() {
            return Err(GpuError::Unsupported(
                "an engine framebuffer for a host's render pass (the host begins its pass on its own framebuffer)"
                    .into(),
            ));
        }
        let mut held: Vec<Arc<Lifetime>> = attachments.iter().map(|a| a.lifetime().clone()).collect();
        held.push(pass.life.clone());
        if let Some(other) = held.iter().find(|l| !l.is_on(&gpu.shared)) {
            return Err(GpuError::WrongDevice { name: other.name().to_string() });
        }
        let expected = 1 + usize::from(pass.depth_format.is_some());
        assert_eq!(attachments.len(), expected, "the render pass has {expected} attachments");
        let views: Vec<vk::ImageView> = attachments.iter().map(|a| a.view()).collect();
        let info = vk::FramebufferCreateInfo::default()
            .render_pass(pass.raw)
            .attachments(&views)
            .width(extent.width)
            .height(extent.height)
            .layers(1);
        // SAFETY: the views are live engine objects of this device (kept by the framebuffer)
        // and as many as the pass's attachments.
        let raw = unsafe { gpu.device().create_framebuffer(&info, None) }.vk("vkCreateFramebuffer")?;
        let life = Lifetime::new(&gpu.shared, "a framebuffer", move |dev| {
            // SAFETY: no recording uses it any more; its attachments are released after it.
            unsafe { dev.raw.destroy_framebuffer(raw, None) };
            drop(held);
        });
        Ok(Self { life, _device: gpu.shared.clone(), raw, pass: pass.raw, extent })
    }

    /// Its size.
    pub fn extent(&self) -> vk::Extent2D {
        self.extent
    }
}

/// An image view the engine makes of an image it does not own (a host's image, a swapchain's).
pub struct ForeignView {
    life: Arc<Lifetime>,
    _device: Arc<DeviceShared>,
    raw: vk::ImageView,
}

impl Tracked for ForeignView {
    fn lifetime(&self) -> &Arc<Lifetime> {
        &self.life
    }
}

impl ForeignView {
    /// A 2D colour view of `image`.
    ///
    /// # Safety
    /// `image` is a live 2D image of this device with `format`, one mip level and one layer,
    /// and it outlives the view and every recording that uses the view.
    pub unsafe fn new(gpu: &Gpu, image: vk::Image, format: vk::Format) -> GpuResult<Self> {
        let info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(super::image::subresource(vk::ImageAspectFlags::COLOR));
        // SAFETY: the caller guarantees `image` per this function's contract.
        let raw = unsafe { gpu.device().create_image_view(&info, None) }.vk("vkCreateImageView")?;
        let life = Lifetime::new(&gpu.shared, "a view of a foreign image", move |dev| {
            // SAFETY: no framebuffer or recording uses it; the image belongs to someone else.
            unsafe { dev.raw.destroy_image_view(raw, None) }
        });
        Ok(Self { life, _device: gpu.shared.clone(), raw })
    }

    /// The view.
    pub fn raw(&self) -> vk::ImageView {
        self.raw
    }
}
