//! Derived fields in the spectral renderer (`--expr`, [`DerivedField`]): the coefficients of
//! every field an expression reads, uploaded element by element, and the fragment shader with
//! the expression spliced in, compiled at run time and kept per expression.

use super::{dev, Result, SpectralRenderer, SpectralView};
use crate::expression::spectral::{DerivedField, DerivedShader};
use crate::gpu::Buffer;
use crate::spectral::SpectralError;
use ash::vk;

impl SpectralRenderer {
    /// Refuses a derived field with what it cannot be drawn with: the per-vertex baseline (it
    /// colours node values), a height field (its surface is the field's), or a step one of its
    /// fields lacks.
    pub(super) fn check_derived_view(&self, view: &SpectralView) -> Result<()> {
        let Some(d) = &view.expression else { return Ok(()) };
        let refuse = |what: &str| {
            Err(SpectralError::Expression(format!("--expr {:?} cannot be drawn {what}", d.expression.text)))
        };
        if view.per_vertex {
            return refuse("per vertex (it is evaluated per pixel)");
        }
        if view.height.is_some() && self.planar {
            return refuse("as a height field");
        }
        d.check_step(&self.mesh, view.field, view.step)
    }

    /// Uploads the coefficients of every field `view`'s derived field reads (and the step's
    /// time), growing the coefficient buffer when they do not fit; a new buffer drops the
    /// pipelines' descriptor sets (the compiled shaders are kept).
    pub(super) fn show_derived(&mut self, view: &SpectralView) -> Result<()> {
        let Some(d) = &view.expression else { return Ok(()) };
        let want = (view.field, view.step, view.expression_key());
        if self.shown == want {
            return Ok(());
        }
        let data = d.padded_values(&self.mesh, view.field, view.step);
        self.upload_values(&data)?;
        self.shown = want;
        Ok(())
    }

    /// Uploads `data` as the coefficient buffer (several field slots per element, or one),
    /// growing the buffer when it does not fit; a new buffer drops every pipeline's descriptor
    /// sets (the compiled shaders are kept).
    pub(super) fn upload_values(&mut self, data: &[f32]) -> Result<()> {
        if data.len() as u64 > self.values.len() {
            let values =
                Buffer::from_slice(&self.gpu, "spectral values", data, vk::BufferUsageFlags::STORAGE_BUFFER)
                    .map_err(dev("uploading the fields' coefficients"))?;
            values.binding().map_err(dev("binding the fields' coefficients"))?;
            self.values = values;
            self.pipelines.clear();
            if let Some(c) = self.cutter.as_mut() {
                c.rebind(&self.gpu, &self._points, &self.values)?;
            }
            if let Some(t) = self.tessellator.as_mut() {
                t.set = None;
            }
            if let Some(i) = self.iso.as_mut() {
                i.pipelines.clear();
            }
            if let Some(v) = self.volume.as_mut() {
                for p in v.pipelines.values_mut() {
                    p.1.clear();
                }
            }
        } else {
            self.values.upload(&self.gpu, 0, data).map_err(dev("uploading the fields' coefficients"))?;
        }
        Ok(())
    }

    /// Compiles `d`'s fragment shader for this mesh unless it was compiled before.
    pub(super) fn derived_shader(&mut self, d: &DerivedField) -> Result<()> {
        if !self.derived_shaders.contains_key(&d.expression.text) {
            let kind = match (self.cutter.is_some(), self.planar) {
                (true, _) => DerivedShader::CutPlanes,
                (false, true) => DerivedShader::Planar,
                (false, false) => DerivedShader::Surface,
            };
            let spirv = d.compile_fragment(kind, self.mesh.elements())?;
            self.derived_shaders.insert(d.expression.text.clone(), spirv);
        }
        Ok(())
    }
}
