//! One way to draw for every capability: a [`Draw`] records what its picture needs outside a
//! render pass (compute, with its declared accesses) and then its draws into any
//! [`DrawTarget`] — galerkin's own offscreen or viewer target, a host's render pass and
//! subpass in the host's viewport, or a host's dynamic rendering. Spectral elements, spacetime
//! slices, fluid cells and particles, and radiosity scenes implement it; the offscreen pictures
//! ([`RenderTarget::draw`]) and the hosts' frames use the same two calls.

use super::draw_target::DrawTarget;
use super::target::{Pixels, RenderTarget};
use crate::gpu::{Gpu, GpuError, GpuFailure, GpuResult, PassKey, Recorder};

/// Something that draws into a [`DrawTarget`] (see the module docs).
pub trait Draw {
    /// What one draw shows: the view, camera, style or values it is drawn with.
    type View<'v>;
    /// The capability's error; device failures in it stay typed ([`GpuFailure`]).
    type Error: GpuFailure + std::fmt::Display;

    /// The capability's error for a device failure while `context`.
    fn device_error(context: &'static str, cause: GpuError) -> Self::Error;

    /// Records the work the draw needs outside the render pass (compute passes, and the
    /// declared reads of the draws that follow), before the render pass that `target` is in
    /// begins. Nothing by default.
    fn record_prepass(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &Self::View<'_>,
    ) -> Result<(), Self::Error> {
        let _ = (rec, target, view);
        Ok(())
    }

    /// Records the draws inside the render pass `target` was begun in, in its viewport
    /// (pipelines for the target's pass are made on first use, or refused with an error
    /// naming why).
    fn record_draw_into(
        &mut self,
        rec: &mut Recorder<'_>,
        target: DrawTarget<'_>,
        view: &Self::View<'_>,
    ) -> Result<(), Self::Error>;
}

/// [`GpuError::Unsupported`] unless `target`'s render pass is of class `key` — the one a
/// renderer of `what` built its pipelines for.
pub fn check_pass(key: PassKey, target: &DrawTarget<'_>, what: &str) -> GpuResult<()> {
    if target.key() == key {
        return Ok(());
    }
    Err(GpuError::Unsupported(format!(
        "drawing {what} into a render pass its pipelines were not made for (make the renderer \
         with that target's render pass)"
    )))
}

impl RenderTarget {
    /// Draws `drawable` into the whole target in one submission — its prepass, the render pass
    /// cleared to `clear`, its draws, the readback — and returns the pixels.
    pub fn draw<D: Draw>(
        &self,
        gpu: &Gpu,
        drawable: &mut D,
        view: &D::View<'_>,
        clear: [f32; 4],
    ) -> Result<Pixels, D::Error> {
        let staging = self.readback_staging(gpu).map_err(|e| D::device_error("making the readback", e))?;
        let target = self.draw_target();
        gpu.run(|rec| -> Result<(), D::Error> {
            drawable.record_prepass(rec, target, view)?;
            self.record_begin(rec, clear);
            let drawn = drawable.record_draw_into(rec, target, view);
            self.record_end(rec);
            drawn?;
            self.record_readback(rec, &staging);
            Ok(())
        })
        .map_err(|e| D::device_error("drawing", e))??;
        self.read_staging(&staging).map_err(|e| D::device_error("reading the picture back", e))
    }
}
