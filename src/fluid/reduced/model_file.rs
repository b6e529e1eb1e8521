//! The reduced fluid model's file (see [`super::model`]'s module docs): the core's safetensors
//! model with the fluid's metadata, trajectories, cells and — for the cavity — its motion
//! model beside it, and the shape checks a loaded model passes.

use std::collections::BTreeMap;
use std::path::Path;

use crate::fluid::FluidError;
use crate::reduce::{ModelExtras, ReducedModel};
use crate::tensor::Tensor;

use super::cavity_motion::CavityMotion;
use super::model::{Provenance, ReducedFluidModel, Trajectory, FLUID_FORMAT, FLUID_VERSION};

impl ReducedFluidModel {
    /// Writes the model (see the module docs; never half-written).
    pub fn save(&self, path: &Path) -> Result<(), FluidError> {
        let mut extras = ModelExtras::default();
        let json =
            |v: &dyn crate::reduce::erased::Json| v.json().map_err(|e| FluidError::State(e.to_string()));
        extras.metadata.insert("format".into(), FLUID_FORMAT.into());
        extras.metadata.insert("version".into(), FLUID_VERSION.to_string());
        extras.metadata.insert("dim".into(), self.dim.to_string());
        extras.metadata.insert("viscosity".into(), json(&self.viscosity)?);
        extras.metadata.insert("frame_time".into(), json(&self.frame_time)?);
        extras.metadata.insert("provenance".into(), json(&self.provenance)?);
        extras
            .arrays
            .insert("cells".into(), Tensor::vector(self.cells.iter().map(|&c| f64::from(c)).collect()));
        for (k, t) in self.trajectories.iter().enumerate() {
            extras.arrays.insert(format!("run{k}/g"), t.g.clone());
            extras.arrays.insert(format!("run{k}/h"), t.h.clone());
            extras.arrays.insert(format!("run{k}/u0"), Tensor::vector(t.u0.clone()));
            extras.arrays.insert(format!("run{k}/f0"), Tensor::vector(t.f0.clone()));
        }
        if let Some(c) = &self.cavity {
            extras.arrays.insert("cavity/map".into(), c.map.clone());
            extras.arrays.insert("cavity/volume".into(), c.volume.clone());
            extras.metadata.insert("cavity_rest_volume".into(), json(&c.rest_volume)?);
        }
        if let Some(g) = &self.flux_grams {
            extras.arrays.insert("flux/M".into(), g.full.clone());
            extras.arrays.insert("flux/N".into(), g.seen.clone());
        }
        self.core.save_with(path, &extras).map_err(FluidError::from)
    }

    /// Reads a model written by [`ReducedFluidModel::save`], checking its format, version and
    /// every tensor's shape.
    pub fn load(path: &Path) -> Result<Self, FluidError> {
        let fail = |m: String| FluidError::File { path: path.to_path_buf(), message: m };
        let (core, extras) = ReducedModel::load_with(path).map_err(FluidError::from)?;
        let get = |k: &str| {
            extras.metadata.get(k).ok_or_else(|| fail(format!("not a reduced fluid model (no `{k}`)")))
        };
        if get("format")? != FLUID_FORMAT {
            return Err(fail(format!("format `{}` is not a reduced fluid model", get("format")?)));
        }
        let version: u32 = get("version")?.parse().map_err(|_| fail("bad version".into()))?;
        if version != FLUID_VERSION {
            return Err(fail(format!(
                "reduced fluid format version {version}; this build reads {FLUID_VERSION}"
            )));
        }
        let parse = |k: &str| -> Result<serde_json::Value, FluidError> {
            serde_json::from_str(get(k)?).map_err(|e| fail(format!("metadata `{k}`: {e}")))
        };
        let dim: usize = get("dim")?.parse().map_err(|_| fail("bad dim".into()))?;
        if !(dim == 2 || dim == 3) {
            return Err(fail(format!("dimension {dim}")));
        }
        let viscosity: f64 = serde_json::from_value(parse("viscosity")?).map_err(|e| fail(e.to_string()))?;
        let frame_time: f64 =
            serde_json::from_value(parse("frame_time")?).map_err(|e| fail(e.to_string()))?;
        if !(viscosity.is_finite() && viscosity >= 0.0) {
            return Err(fail(format!("metadata `viscosity` is {viscosity}: must be finite and ≥ 0")));
        }
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(fail(format!("metadata `frame_time` is {frame_time}: must be positive and finite")));
        }
        let provenance: Provenance =
            serde_json::from_value(parse("provenance")?).map_err(|e| fail(format!("provenance: {e}")))?;
        let mut trajectories = Vec::new();
        for k in 0..provenance.runs.len() {
            let array = |q: &str| {
                extras
                    .arrays
                    .get(&format!("run{k}/{q}"))
                    .cloned()
                    .ok_or_else(|| fail(format!("no trajectory run{k}/{q}")))
            };
            let t = Trajectory {
                g: array("g")?,
                h: array("h")?,
                u0: array("u0")?.into_data(),
                f0: array("f0")?.into_data(),
            };
            trajectories.push(t);
        }
        let raw = extras.arrays.get("cells").ok_or_else(|| fail("no `data/cells`".into()))?;
        let want = provenance.mesh.cells * (dim + 1);
        if raw.len() != want {
            return Err(fail(format!(
                "`data/cells` has {} entries, {} cells need {want}",
                raw.len(),
                provenance.mesh.cells
            )));
        }
        let nv = provenance.mesh.vertices as f64;
        if let Some(i) = raw.data().iter().position(|&c| !(c >= 0.0 && c < nv && c.fract() == 0.0)) {
            return Err(fail(format!("`data/cells` entry {i} is not a vertex index below {nv}")));
        }
        let cells = raw.data().iter().map(|&c| c as u32).collect();
        let cavity = match (extras.arrays.get("cavity/map"), extras.arrays.get("cavity/volume")) {
            (Some(map), Some(volume)) => {
                let rest_volume: f64 = serde_json::from_value(parse("cavity_rest_volume")?)
                    .map_err(|e| fail(format!("cavity_rest_volume: {e}")))?;
                if !(f64::is_finite(rest_volume) && rest_volume > 0.0) {
                    return Err(fail(format!(
                        "metadata `cavity_rest_volume` is {rest_volume}: must be positive"
                    )));
                }
                if map.shape() != [provenance_dim(&core, "g"), 5] || volume.shape() != [5, 5, 5] {
                    return Err(fail(format!(
                        "the cavity's motion model has shapes {:?} and {:?}",
                        map.shape(),
                        volume.shape()
                    )));
                }
                Some(CavityMotion { map: map.clone(), volume: volume.clone(), rest_volume })
            }
            _ => None,
        };
        let flux_grams = match (extras.arrays.get("flux/M"), extras.arrays.get("flux/N")) {
            (Some(m), Some(n)) => {
                let mf = provenance_dim(&core, "f");
                if m.shape() != [mf, mf] || n.shape() != [mf, mf] {
                    return Err(fail(format!(
                        "`data/flux/M` and `data/flux/N` have shapes {:?} and {:?}; the flux basis has {mf} modes",
                        m.shape(),
                        n.shape()
                    )));
                }
                if m.data().iter().chain(n.data()).any(|x| !x.is_finite()) {
                    return Err(fail(
                        "`data/flux/M` or `data/flux/N` holds a value that is not finite".into(),
                    ));
                }
                Some(super::exact_projection::FluxVelocityGrams { full: m.clone(), seen: n.clone() })
            }
            (None, None) => None,
            _ => return Err(fail("one of `data/flux/M` and `data/flux/N` without the other".into())),
        };
        let model =
            Self { core, dim, viscosity, frame_time, provenance, trajectories, cells, cavity, flux_grams };
        model.check_shapes().map_err(|e| fail(e.to_string()))?;
        Ok(model)
    }

    /// Checks that every tensor has the shape its bases give.
    pub(super) fn check_shapes(&self) -> Result<(), FluidError> {
        let (mu, mf, mg, mh, md) =
            (self.dim_of("u"), self.dim_of("f"), self.dim_of("g"), self.dim_of("h"), self.dim_of("d"));
        if mu == 0 || mf == 0 || mg == 0 {
            return Err(FluidError::State("the model lacks one of the bases u, f, g".into()));
        }
        let mut want: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        want.insert("A", vec![mu, mu, mf]);
        want.insert("L", vec![mu, mu]);
        want.insert("P", vec![mu, mf, mg]);
        let mut v = vec![mu, mu];
        v.extend(std::iter::repeat_n(mg, self.dim));
        want.insert("V", v);
        if mh > 0 {
            want.insert("Ah", vec![mu, mu, mh]);
        }
        if let Some(t) = self.tensor("H") {
            let mut hs = vec![mh];
            hs.extend(std::iter::repeat_n(2 * mg, self.dim));
            if t.shape() != hs.as_slice() {
                return Err(FluidError::State(format!(
                    "tensor H has shape {:?}, its bases give {hs:?}",
                    t.shape()
                )));
            }
        }
        if md > 0 {
            want.insert("D", vec![md, mf]);
            if mh > 0 {
                want.insert("Dh", vec![md, mh]);
            }
        }
        for (name, shape) in want {
            match self.tensor(name) {
                Some(t) if t.shape() == shape.as_slice() => {}
                Some(t) => {
                    return Err(FluidError::State(format!(
                        "tensor {name} has shape {:?}, its bases give {shape:?}",
                        t.shape()
                    )))
                }
                None => return Err(FluidError::State(format!("tensor {name} is missing"))),
            }
        }
        for (k, t) in self.trajectories.iter().enumerate() {
            if t.g.order() != 2
                || t.g.shape()[1] != mg
                || t.h.order() != 2
                || t.h.shape()[1] != mh
                || t.g.shape()[0] != t.h.shape()[0]
                || t.u0.len() != mu
                || t.f0.len() != mf
            {
                return Err(FluidError::State(format!("trajectory of run {k} does not fit the bases")));
            }
        }
        Ok(())
    }
}

/// The reduced dimension of basis `name` in `core` (0 without it).
fn provenance_dim(core: &ReducedModel, name: &str) -> usize {
    core.bases.get(name).map_or(0, |b| b.reduced_dim())
}
