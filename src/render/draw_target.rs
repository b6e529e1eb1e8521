//! Where a draw lands: inside a render pass someone has begun — galerkin's own offscreen or
//! viewer target, or a host application's render pass and framebuffer — and the rectangle of
//! that framebuffer the draw covers. Renderers take a [`DrawTarget`], so the same draw records
//! into the engine's images and into a host's frame.

use ash::vk;

use super::target::{ColorFormat, RenderTarget};
use crate::gpu::{GpuError, GpuResult, PassKey, RenderPass, Viewport};

/// A render pass being recorded and the viewport a draw fills in it (see the module docs).
#[derive(Copy, Clone, Debug)]
pub struct DrawTarget<'a> {
    pass: &'a RenderPass,
    format: ColorFormat,
    viewport: Viewport,
}

impl<'a> DrawTarget<'a> {
    /// Draws inside `pass` (an engine pass, or a host's described by
    /// [`RenderPass::from_host`]) in `viewport` of its framebuffer. The viewport must lie
    /// inside the framebuffer the pass is begun on (the host's to ensure for its own passes).
    /// [`GpuError::Unsupported`] if the pass's colour format is not one galerkin writes.
    pub fn new(pass: &'a RenderPass, viewport: Viewport) -> GpuResult<Self> {
        let format = ColorFormat::of_attachment(pass.color_format()).ok_or_else(|| {
            GpuError::Unsupported(format!(
                "drawing into a colour attachment of format {:?}",
                pass.color_format()
            ))
        })?;
        if viewport.width == 0 || viewport.height == 0 {
            return Err(GpuError::Unsupported(format!(
                "an empty viewport ({}×{} pixels)",
                viewport.width, viewport.height
            )));
        }
        Ok(Self { pass, format, viewport })
    }

    /// [`GpuError::Unsupported`] unless the render pass has a depth attachment — which the
    /// draws of `what` need: they order surfaces, and edge lines against faces, by depth.
    pub fn require_depth(&self, what: &str) -> GpuResult<()> {
        if self.pass.depth_format().is_some() {
            return Ok(());
        }
        Err(GpuError::Unsupported(format!(
            "drawing {what} in a render pass without a depth attachment (they order surfaces and \
             edges by depth; give the subpass a depth attachment)"
        )))
    }

    /// The render pass the draw is recorded in.
    pub fn render_pass(&self) -> &'a RenderPass {
        self.pass
    }

    /// Which pipelines can draw here (renderers cache theirs by it).
    pub fn key(&self) -> PassKey {
        self.pass.key()
    }

    /// What the colour attachment holds: colours (RGBA8) or raw values (RGBA32F).
    pub fn format(&self) -> ColorFormat {
        self.format
    }

    /// The rectangle the draw covers.
    pub fn viewport(&self) -> Viewport {
        self.viewport
    }

    /// The viewport's size.
    pub fn extent(&self) -> vk::Extent2D {
        self.viewport.extent()
    }

    /// The viewport's width / height.
    pub fn aspect(&self) -> f64 {
        self.viewport.aspect()
    }
}

impl<'a> From<&'a RenderTarget> for DrawTarget<'a> {
    fn from(target: &'a RenderTarget) -> Self {
        target.draw_target()
    }
}
