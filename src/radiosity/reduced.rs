//! The reduced radiosity at run time (seed 000 §8.2–8.3): project the geometry, predict the
//! reduced visibility (Eq. 17), evaluate Table 2's chain on the premultiplied tensors, lift
//! the radiosity to the faces.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use std::time::Instant;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use super::error::RadiosityError;
use super::solve::Rgb;
use super::visibility::LearnedVisibility;
use crate::reduce::ReducedModel;
use crate::tensor::Tensor;

/// The reduced model and its learned visibility.
#[derive(Clone, Debug)]
pub struct ReducedRadiosity {
    model: ReducedModel,
    visibility: LearnedVisibility,
    emission_hat: Vec<f64>,
    faces: usize,
}

/// Where a reduced frame's time went (seconds).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReducedTimes {
    /// `ĝ = B_gᵀ g`.
    pub project: f64,
    /// Eq. 17 and `v̂ = B_vᵀ V x`.
    pub visibility: f64,
    /// Table 2's chain on the reduced tensors.
    pub chain: f64,
    /// `b = B_b b̂`.
    pub lift: f64,
}

impl ReducedRadiosity {
    /// Assembles the run-time model (checks that the model computes `b` from `g`, `v`, `e`).
    pub fn new(
        model: ReducedModel,
        visibility: LearnedVisibility,
        emission_hat: Vec<f64>,
        faces: usize,
    ) -> Result<Self, RadiosityError> {
        let bad = |m: String| RadiosityError::Solve(format!("reduced radiosity model: {m}"));
        model.check().map_err(|e| bad(e.to_string()))?;
        for (name, want) in [("g", None), ("b", Some(3 * faces))] {
            let b = model.basis(name).ok_or_else(|| bad(format!("no basis `{name}`")))?;
            if want.is_some_and(|w| w != b.full_dim()) {
                return Err(bad(format!("basis `{name}` has {} rows for {faces} faces", b.full_dim())));
            }
        }
        Ok(Self { model, visibility, emission_hat, faces })
    }

    /// The core's reduced model.
    pub fn model(&self) -> &ReducedModel {
        &self.model
    }

    /// The learned visibility.
    pub fn learned_visibility(&self) -> &LearnedVisibility {
        &self.visibility
    }

    /// Number of faces.
    pub fn faces(&self) -> usize {
        self.faces
    }

    /// Reduced dimension of every basis of Table 2, by name (read off the reduced tensors).
    pub fn dimensions(&self) -> BTreeMap<String, usize> {
        let mut d = BTreeMap::new();
        for (tensor, axes) in [
            ("N", ["n", "g", "g"]),
            ("S", ["sh", "n", "g"]),
            ("R", ["r", "g", "g"]),
            ("C", ["c", "sh", "sh"]),
            ("D", ["dp", "c", "v"]),
            ("A", ["a", "n", "n"]),
            ("E", ["b", "b", "dp"]),
        ] {
            if let Some(t) = self.model.tensor(tensor) {
                for (name, &m) in axes.iter().zip(t.shape()) {
                    d.insert(name.to_string(), m);
                }
            }
        }
        d
    }

    /// Radiosity per face for vertex positions `g`, and where the time went.
    pub fn evaluate(&self, g: &[f64]) -> Result<(Vec<Rgb>, ReducedTimes), RadiosityError> {
        let err = |e: crate::reduce::ReduceError| RadiosityError::Solve(e.to_string());
        let mut times = ReducedTimes::default();
        let t0 = Instant::now();
        let ghat = self.model.project_input("g", g).map_err(err)?;
        let t1 = Instant::now();
        let (vhat, _) = self.visibility.predict(&ghat);
        let t2 = Instant::now();
        let inputs: BTreeMap<&str, &[f64]> =
            [("g", ghat.as_slice()), ("v", vhat.as_slice()), ("e", self.emission_hat.as_slice())].into();
        let bhat = self.model.evaluate(&inputs).map_err(err)?;
        let t3 = Instant::now();
        let b = self.model.lift(bhat.data()).map_err(err)?;
        let t4 = Instant::now();
        times.project = (t1 - t0).as_secs_f64();
        times.visibility = (t2 - t1).as_secs_f64();
        times.chain = (t3 - t2).as_secs_f64();
        times.lift = (t4 - t3).as_secs_f64();
        let n = self.faces;
        Ok(((0..n).map(|i| [b[i], b[n + i], b[2 * n + i]]).collect(), times))
    }
}

/// The `format` metadata of a reduced radiosity's learned-visibility file.
pub const FORMAT: &str = "galerkin-reduced-radiosity";
/// Its version.
pub const VERSION: u32 = 1;

impl ReducedRadiosity {
    /// Writes `dir/model.safetensors` (the core's reduced model: Table 2's premultiplied
    /// tensors and the bases of `g` and `b`) and `dir/visibility.safetensors` (`B_gᵀ G`,
    /// `B_vᵀ V`, `ê`, f64), each to a temporary name first.
    pub fn save(&self, dir: &Path) -> Result<(), RadiosityError> {
        let fail = |detail: String| RadiosityError::Obj { path: dir.to_path_buf(), message: detail };
        std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string()))?;
        self.model.save(&dir.join("model.safetensors")).map_err(|e| fail(e.to_string()))?;
        let bytes = |t: &[f64]| t.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
        let entries = [
            (
                "geometry",
                bytes(self.visibility.geometry().data()),
                self.visibility.geometry().shape().to_vec(),
            ),
            (
                "visibility",
                bytes(self.visibility.visibility().data()),
                self.visibility.visibility().shape().to_vec(),
            ),
            ("emission", bytes(&self.emission_hat), vec![self.emission_hat.len()]),
        ];
        let views = entries
            .iter()
            .map(|(n, b, s)| TensorView::new(Dtype::F64, s.clone(), b).map(|v| (n.to_string(), v)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| fail(e.to_string()))?;
        let meta: HashMap<String, String> = [
            ("format".to_string(), FORMAT.to_string()),
            ("version".to_string(), VERSION.to_string()),
            ("faces".to_string(), self.faces.to_string()),
        ]
        .into();
        let buffer = safetensors::serialize(views, Some(meta)).map_err(|e| fail(e.to_string()))?;
        let path = dir.join("visibility.safetensors");
        let tmp = dir.join(format!(".visibility.safetensors.{}.tmp", std::process::id()));
        std::fs::write(&tmp, buffer).map_err(|e| fail(e.to_string()))?;
        std::fs::rename(&tmp, &path).map_err(|e| fail(e.to_string()))
    }

    /// Reads what [`ReducedRadiosity::save`] wrote; errors name the file and what is wrong.
    pub fn load(dir: &Path) -> Result<Self, RadiosityError> {
        let model = ReducedModel::load(&dir.join("model.safetensors")).map_err(|e| RadiosityError::Obj {
            path: dir.join("model.safetensors"),
            message: e.to_string(),
        })?;
        let path = dir.join("visibility.safetensors");
        let fail = |m: String| RadiosityError::Obj { path: path.clone(), message: m };
        let bytes = std::fs::read(&path).map_err(|e| fail(e.to_string()))?;
        let (_, meta) = SafeTensors::read_metadata(&bytes).map_err(|e| fail(e.to_string()))?;
        let meta = meta.metadata().clone().unwrap_or_default();
        if meta.get("format").map(String::as_str) != Some(FORMAT) {
            return Err(fail(format!("not a {FORMAT} file")));
        }
        if meta.get("version").and_then(|v| v.parse::<u32>().ok()).is_none_or(|v| v > VERSION) {
            return Err(fail(format!(
                "version {:?} is not one this build reads (≤ {VERSION})",
                meta.get("version")
            )));
        }
        let faces: usize =
            meta.get("faces").and_then(|v| v.parse().ok()).ok_or_else(|| fail("no face count".into()))?;
        let file = SafeTensors::deserialize(&bytes).map_err(|e| fail(e.to_string()))?;
        let read = |name: &str| -> Result<Tensor, RadiosityError> {
            let v = file.tensor(name).map_err(|e| fail(format!("{name}: {e}")))?;
            if v.dtype() != Dtype::F64 {
                return Err(fail(format!("{name}: expected f64")));
            }
            let data = v
                .data()
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
                .collect();
            Tensor::from_vec(v.shape(), data).map_err(|e| fail(format!("{name}: {e}")))
        };
        let learned = LearnedVisibility::new(read("geometry")?, read("visibility")?)
            .map_err(|e| fail(e.to_string()))?;
        let emission = read("emission")?.into_data();
        Self::new(model, learned, emission, faces).map_err(|e| fail(e.to_string()))
    }
}

/// Relative error `‖b − b_ref‖ / ‖b_ref‖` over faces and channels, weighted by face area.
pub fn relative_error(b: &[Rgb], reference: &[Rgb], areas: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((x, y), a) in b.iter().zip(reference).zip(areas) {
        for c in 0..3 {
            num += a * (x[c] - y[c]).powi(2);
            den += a * y[c].powi(2);
        }
    }
    (num / den.max(1e-300)).sqrt()
}
