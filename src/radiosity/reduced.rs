//! The reduced radiosity at run time (seed 000 §8.2–8.3): project the geometry, predict the
//! reduced visibility (Eq. 17), evaluate Table 2's chain on the premultiplied tensors, lift
//! the radiosity to the faces.
//!
//! Direct light both ways of §9: area lights in the openings are a fixed emission inside the
//! model (`ê` precomputed); the sky's light is computed at run time outside it ([`SkyLight`]):
//! `eᵢ = ρᵢ Σ_{j opening} w_ij F⁰_ij π L(d_ij)` from the current geometry (`F⁰` the form factor
//! without visibility) and the visibility of face–opening pairs blended with Eq. 17's weights,
//! `w_ij = Σ_t x_t Vis_t(i, j)` (stored as bits per training configuration), then projected.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use super::error::RadiosityError;
use super::estimate::{sample_spacing, stability, CrossValidation, Estimate};
use super::form_factor::{facing, unoccluded_form_factor, NearField};
use super::lighting::sky_radiance;
use super::mesh::SceneMesh;
use super::scene::{LightMode, Lights};
use super::solve::Rgb;
use super::visibility::LearnedVisibility;
use crate::reduce::provenance::Provenance;
use crate::reduce::ReducedModel;
use crate::tensor::Tensor;

mod file;
pub use file::{FORMAT, VERSION};

/// The reduced model and its learned visibility.
#[derive(Clone, Debug)]
pub struct ReducedRadiosity {
    model: ReducedModel,
    visibility: LearnedVisibility,
    emission_hat: Vec<f64>,
    faces: usize,
    sky: Option<SkyLight>,
    trained_near: TrainedNearField,
    /// The error estimate's offline part ([`super::estimate`]); `None` for models trained
    /// without it.
    validation: Option<CrossValidation>,
    /// Where the model came from (`None` for models saved before it was recorded).
    provenance: Option<Provenance>,
}

/// The form factors a model's training solves used: what its full-space ground truth is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrainedNearField {
    /// Centroid form factors (Eq. 15 with the regularised near field): Table 2 as printed.
    Centroid,
    /// The exact polygon form factors of near pairs ([`super::near_correction`]).
    Exact,
}

/// The sky's direct light, computed at run time (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct SkyLight {
    /// The sky (zenith radiance, ground albedo).
    pub lights: Lights,
    /// The opening faces.
    pub openings: Vec<u32>,
    /// Per training configuration, `Vis(i, openings[o])` at bit `i·openings.len() + o`.
    pub bits: Vec<Vec<u64>>,
    /// The near-field treatment the model was trained with.
    pub near: NearField,
}

impl SkyLight {
    /// `e` for `mesh` with Eq. 17's weights `x` over the training configurations.
    pub fn emission(&self, mesh: &SceneMesh, x: &[f64]) -> Vec<Rgb> {
        let g = mesh.geometry();
        let no = self.openings.len();
        let used: Vec<(usize, f64)> = x.iter().copied().enumerate().filter(|(_, w)| *w > 0.0).collect();
        (0..mesh.len())
            .map(|i| {
                if mesh.kind[i].is_opening() {
                    return [0.0; 3];
                }
                let mut irradiance = [0.0; 3];
                for (o, &j) in self.openings.iter().enumerate() {
                    let j = j as usize;
                    if !facing(&g, i, j) {
                        continue;
                    }
                    let k = i * no + o;
                    let w: f64 = used
                        .iter()
                        .filter(|(t, _)| self.bits[*t][k / 64] >> (k % 64) & 1 == 1)
                        .map(|(_, w)| w)
                        .sum();
                    if w > 0.0 {
                        let f = w * unoccluded_form_factor(&g, i, j, self.near);
                        let l = sky_radiance(&self.lights, (g.centroids[j] - g.centroids[i]).normalize());
                        for c in 0..3 {
                            irradiance[c] += f * std::f64::consts::PI * l[c];
                        }
                    }
                }
                [0, 1, 2].map(|c| mesh.albedo[i][c] * irradiance[c])
            })
            .collect()
    }
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
    /// The sky's direct light (sky mode only).
    pub direct: f64,
    /// The error estimate and the stability check ([`ReducedRadiosity::evaluate_estimated`]).
    pub estimate: f64,
}

impl ReducedRadiosity {
    /// Assembles the run-time model (checks that the model computes `b` from `g`, `v`, `e`).
    pub fn new(
        model: ReducedModel,
        visibility: LearnedVisibility,
        emission_hat: Vec<f64>,
        faces: usize,
        sky: Option<SkyLight>,
        trained_near: TrainedNearField,
    ) -> Result<Self, RadiosityError> {
        let bad = |m: String| RadiosityError::Solve(format!("reduced radiosity model: {m}"));
        model.check().map_err(|e| bad(e.to_string()))?;
        for (name, want) in [("g", None), ("b", Some(3 * faces))] {
            let b = model.basis(name).ok_or_else(|| bad(format!("no basis `{name}`")))?;
            if want.is_some_and(|w| w != b.full_dim()) {
                return Err(bad(format!("basis `{name}` has {} rows for {faces} faces", b.full_dim())));
            }
        }
        let t = visibility.geometry().shape()[1];
        if let Some(q) = model.tensor("Q") {
            if q.shape().get(2) != Some(&t) {
                return Err(bad(format!(
                    "the operator correction has {:?} configurations, the learned visibility {t}",
                    q.shape().get(2)
                )));
            }
        }
        if let Some(sky) = &sky {
            let words = (faces * sky.openings.len()).div_ceil(64);
            if sky.bits.len() != t || sky.bits.iter().any(|b| b.len() != words) {
                return Err(bad(format!(
                    "the sky's visibility bits do not match {t} configurations of {faces} faces"
                )));
            }
        }
        Ok(Self {
            model,
            visibility,
            emission_hat,
            faces,
            sky,
            trained_near,
            validation: None,
            provenance: None,
        })
    }

    /// The model with the error estimate's offline part ([`super::estimate`]), checked to have
    /// one value per training configuration.
    pub fn with_estimate(mut self, validation: CrossValidation) -> Result<Self, RadiosityError> {
        let t = self.visibility.geometry().shape()[1];
        if validation.samples() != t {
            return Err(RadiosityError::Solve(format!(
                "the error estimate has {} samples, the learned visibility {t}",
                validation.samples()
            )));
        }
        self.validation = Some(validation);
        Ok(self)
    }

    /// The model with its provenance: the scene file and its content's hash, the training
    /// options and samples, the engine.
    pub fn with_provenance(mut self, provenance: Provenance) -> Self {
        self.provenance = Some(provenance);
        self
    }

    /// Where the model came from, if recorded.
    pub fn provenance(&self) -> Option<&Provenance> {
        self.provenance.as_ref()
    }

    /// The scene file to use with this model: `given`, checked to be the scene the model was
    /// trained on (its content's hash), or without one the scene file the model names. A
    /// model that does not record its scene needs one given, and cannot check it.
    pub fn scene_file(&self, given: Option<&Path>) -> Result<std::path::PathBuf, RadiosityError> {
        let fail = |path: &Path, message: String| RadiosityError::File { path: path.to_path_buf(), message };
        let path = match (given, &self.provenance) {
            (Some(p), _) => p.to_path_buf(),
            (None, Some(p)) => std::path::PathBuf::from(&p.scene),
            (None, None) => {
                return Err(RadiosityError::Mesh(
                    "the model does not record the scene it was trained on (trained before models did): name the scene file".into(),
                ))
            }
        };
        if let Some(p) = &self.provenance {
            let scene = super::any_scene::AnyScene::load(&path, None)?;
            p.check_scene(&path, &scene.content_sha256(&path)?).map_err(|m| fail(&path, m))?;
        }
        Ok(path)
    }

    /// The error estimate's offline part, if the model has one.
    pub fn cross_validation(&self) -> Option<&CrossValidation> {
        self.validation.as_ref()
    }

    /// The error estimate's offline part for this model ([`super::estimate`]): each training
    /// configuration evaluated with itself left out of Eq. 17 against its own full solve, the
    /// basis's floor there, and the samples' spacing. Errors are over the faces `receiving`.
    /// A sky-lit model's left-out evaluation takes the configuration's own direct light
    /// (projected), not the run time's blend of visibility bits.
    pub fn cross_validate(
        &self,
        configurations: &[super::train::Configuration],
        receiving: &[usize],
    ) -> Result<CrossValidation, RadiosityError> {
        use rayon::prelude::*;
        let err = RadiosityError::from;
        let basis = self.model.basis("b").ok_or_else(|| RadiosityError::Solve("no basis `b`".into()))?;
        let results: Vec<(f64, f64)> = configurations
            .par_iter()
            .enumerate()
            .map(|(t, c)| {
                let ghat = self.model.project_input("g", &c.g).map_err(err)?;
                let (vhat, x) = self.visibility.predict_without(&ghat, Some(t));
                let ehat = match &self.sky {
                    Some(_) => basis.project(&super::chain::stack_channels(&c.emission)),
                    None => self.emission_hat.clone(),
                };
                let (bhat, _) = self.solve_reduced(&ghat, &vhat, &x, &ehat)?;
                let b = self.unstack(&basis.lift(&bhat));
                let areas = &c.geometry.areas;
                let left_out = super::compare::relative_error_over(&b, &c.radiosity, areas, receiving);
                let floor = super::compare::relative_error_over(
                    &self.best_fit(&c.radiosity),
                    &c.radiosity,
                    areas,
                    receiving,
                );
                Ok((left_out, floor))
            })
            .collect::<Result<_, RadiosityError>>()?;
        let (left_out, floor) = results.into_iter().unzip();
        CrossValidation::new(left_out, floor, sample_spacing(self.visibility.geometry()))
            .map_err(|e| RadiosityError::Solve(format!("the error estimate: {e}")))
    }

    /// Per-face R, G, B from a vector stacked by channel.
    fn unstack(&self, b: &[f64]) -> Vec<Rgb> {
        let n = self.faces;
        (0..n).map(|i| [b[i], b[n + i], b[2 * n + i]]).collect()
    }

    /// The core's reduced model.
    pub fn model(&self) -> &ReducedModel {
        &self.model
    }

    /// The learned visibility.
    pub fn learned_visibility(&self) -> &LearnedVisibility {
        &self.visibility
    }

    /// Solves Eq. 17 in `form` from now on ([`super::visibility::Eq17`]).
    pub fn set_eq17(&mut self, form: super::visibility::Eq17) {
        self.visibility.set_form(form);
    }

    /// Number of faces.
    pub fn faces(&self) -> usize {
        self.faces
    }

    /// Reduced dimension of every basis of Table 2, by name (read off the reduced tensors).
    pub fn dimensions(&self) -> BTreeMap<String, usize> {
        self.model
            .tensors()
            .flat_map(|(_, axes, t)| axes.iter().cloned().zip(t.shape().iter().copied()))
            .collect()
    }

    /// Whether the model's reduced operator is corrected at the training configurations
    /// ([`super::operator_correction`]).
    pub fn has_operator_correction(&self) -> bool {
        self.model.tensor("Q").is_some()
    }

    /// The form factors the model's training solves used (its ground truth).
    pub fn trained_near_field(&self) -> TrainedNearField {
        self.trained_near
    }

    /// How the model was trained to be lit.
    pub fn light_mode(&self) -> LightMode {
        if self.sky.is_some() {
            LightMode::Sky
        } else {
            LightMode::Area
        }
    }

    /// Refuses a mesh of another face count than the model's.
    fn check_faces(&self, mesh: &SceneMesh) -> Result<(), RadiosityError> {
        if mesh.len() != self.faces {
            return Err(RadiosityError::Mesh(format!(
                "the model has {} faces, the mesh {}",
                self.faces,
                mesh.len()
            )));
        }
        Ok(())
    }

    /// `ê`: the area lights' stored projection, or the sky's direct light at `mesh` (Eq. 17's
    /// weights `x`) projected on `B_b`.
    fn reduced_emission(&self, mesh: &SceneMesh, x: &[f64]) -> Result<Vec<f64>, RadiosityError> {
        match &self.sky {
            Some(sky) => {
                let e = sky.emission(mesh, x);
                let basis =
                    self.model.basis("b").ok_or_else(|| RadiosityError::Solve("no basis `b`".into()))?;
                Ok(basis.project(&super::chain::stack_channels(&e)))
            }
            None => Ok(self.emission_hat.clone()),
        }
    }

    /// The chain's reduced inputs at `mesh` — `ĝ`, `v̂`, Eq. 17's weights `x` — and `ê`, with
    /// the projection's, Eq. 17's and the direct light's times in `times`.
    #[allow(clippy::type_complexity)]
    fn reduced_inputs(
        &self,
        mesh: &SceneMesh,
        times: &mut ReducedTimes,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>), RadiosityError> {
        let err = RadiosityError::from;
        self.check_faces(mesh)?;
        let t0 = Instant::now();
        let ghat = self.model.project_input("g", &mesh.g()).map_err(err)?;
        let t1 = Instant::now();
        let (vhat, x) = self.visibility.predict(&ghat);
        let t2 = Instant::now();
        let ehat = self.reduced_emission(mesh, &x)?;
        times.project = (t1 - t0).as_secs_f64();
        times.direct = t2.elapsed().as_secs_f64();
        times.visibility = (t2 - t1).as_secs_f64();
        Ok((ghat, vhat, x, ehat))
    }

    /// Radiosity per face of `mesh` (the scene's topology at some parameters), and where the
    /// time went.
    pub fn evaluate(&self, mesh: &SceneMesh) -> Result<(Vec<Rgb>, ReducedTimes), RadiosityError> {
        let err = RadiosityError::from;
        let mut times = ReducedTimes::default();
        let (ghat, vhat, x, ehat) = self.reduced_inputs(mesh, &mut times)?;
        let t2 = Instant::now();
        let mut inputs = self.chain_inputs(&ghat, &vhat, &x);
        inputs.insert("e", ehat.as_slice());
        let bhat = self.model.evaluate(&inputs).map_err(err)?;
        let t3 = Instant::now();
        let b = self.model.lift(bhat.data()).map_err(err)?;
        times.chain = (t3 - t2).as_secs_f64();
        times.lift = t3.elapsed().as_secs_f64();
        let n = self.faces;
        Ok(((0..n).map(|i| [b[i], b[n + i], b[2 * n + i]]).collect(), times))
    }

    /// `b` projected on the radiosity basis and lifted back, `B_b B_bᵀ b`: the closest any
    /// radiosity of the model can come to `b` (per face, R, G, B).
    pub fn best_fit(&self, b: &[Rgb]) -> Vec<Rgb> {
        let n = self.faces;
        let Some(basis) = self.model.basis("b") else { return vec![[f64::NAN; 3]; b.len()] };
        let fit = basis.lift(&basis.project(&super::chain::stack_channels(b)));
        (0..n).map(|i| [fit[i], fit[n + i], fit[2 * n + i]]).collect()
    }

    /// The chain's reduced inputs `ĝ`, `v̂` and, with the operator correction, Eq. 17's
    /// weights `x` (the emission `ê` is added by the caller that needs it).
    fn chain_inputs<'a>(
        &self,
        ghat: &'a [f64],
        vhat: &'a [f64],
        x: &'a [f64],
    ) -> BTreeMap<&'static str, &'a [f64]> {
        let mut inputs: BTreeMap<&str, &[f64]> = [("g", ghat), ("v", vhat)].into();
        if self.has_operator_correction() {
            inputs.insert("x", x);
        }
        inputs
    }

    /// The reduced operator `M̂ = Î − Ê ⊗₂ p̂ (− Q̂ ⊗₂ x)` at `mesh` (m_b × m_b): what
    /// [`Self::evaluate`] inverts — `B_bᵀ (I − ρF̂) B_b` with `F̂` the reduced chain's form
    /// factors (Table 2) — for checking it against the exact operator projected on `B_b`.
    pub fn reduced_operator(&self, mesh: &SceneMesh) -> Result<Tensor, RadiosityError> {
        let err = RadiosityError::from;
        let ghat = self.model.project_input("g", &mesh.g()).map_err(err)?;
        let (vhat, x) = self.visibility.predict(&ghat);
        let expr = super::chain::radiosity_operator(self.has_operator_correction());
        self.model.evaluate_expression(&expr, &self.chain_inputs(&ghat, &vhat, &x)).map_err(err)
    }

    /// The smallest real part of the reduced operator's eigenvalues at `mesh`. The full
    /// operator `I − ρF` has every eigenvalue's real part at least `1 − ρ(ρF) > 0` (albedo
    /// below 1, rows of F summing to at most 1); a reduced operator whose smallest real part
    /// is near 0 or below has left the physics, and its radiosity is not to be trusted.
    pub fn operator_margin(&self, mesh: &SceneMesh) -> Result<f64, RadiosityError> {
        Ok(stability(&self.reduced_operator(mesh)?)?.1)
    }

    /// Eq. 16 on the reduced inputs: the chain's reduced form factors `p̂` (Table 2), the
    /// reduced operator `M̂ = Î − Ê ⊗₂ p̂ (− Q̂ ⊗₂ x)` formed from them, and `b̂ = M̂⁻¹ ê` by LU —
    /// the model's composition ([`super::chain::radiosity_corrected`]) with `M̂` kept for the
    /// stability check. Returns `b̂` and `M̂`.
    fn solve_reduced(
        &self,
        ghat: &[f64],
        vhat: &[f64],
        x: &[f64],
        ehat: &[f64],
    ) -> Result<(Vec<f64>, Tensor), RadiosityError> {
        let err = RadiosityError::from;
        let tensor_err = |e: crate::tensor::TensorError| RadiosityError::Solve(e.to_string());
        let inputs = self.chain_inputs(ghat, vhat, x);
        let phat = self.model.evaluate_expression(&super::chain::form_factors(), &inputs).map_err(err)?;
        let tensor = |name: &str| {
            self.model
                .tensor(name)
                .ok_or_else(|| RadiosityError::Solve(format!("the model has no tensor {name}")))
        };
        let mut operator = tensor("I")?.clone();
        let reflection = tensor("E")?.contract_axes(&[(2, phat.data())]).map_err(tensor_err)?;
        for (o, k) in operator.data_mut().iter_mut().zip(reflection.data()) {
            *o -= k;
        }
        if let Some(q) = self.model.tensor("Q") {
            let correction = q.contract_axes(&[(2, x)]).map_err(tensor_err)?;
            for (o, c) in operator.data_mut().iter_mut().zip(correction.data()) {
                *o -= c;
            }
        }
        let bhat = crate::tensor::solve("the reduced operator M̂", &operator, ehat).map_err(tensor_err)?;
        Ok((bhat, operator))
    }

    /// Radiosity per face of `mesh` as [`Self::evaluate`] computes it, with its error estimate
    /// and stability check ([`super::estimate`]). `estimate.error` is `NaN` for a model
    /// trained without the estimate (the margin is checked all the same).
    pub fn evaluate_estimated(
        &self,
        mesh: &SceneMesh,
    ) -> Result<(Vec<Rgb>, ReducedTimes, Estimate), RadiosityError> {
        let err = RadiosityError::from;
        let mut times = ReducedTimes::default();
        let (ghat, vhat, x, ehat) = self.reduced_inputs(mesh, &mut times)?;
        let t2 = Instant::now();
        let (bhat, operator) = self.solve_reduced(&ghat, &vhat, &x, &ehat)?;
        let t3 = Instant::now();
        let (stability, margin) = stability(&operator)?;
        let error = match &self.validation {
            Some(v) => v.estimate(&ghat, &x, self.visibility.geometry()),
            None => f64::NAN,
        };
        let t4 = Instant::now();
        let b = self.model.lift(&bhat).map_err(err)?;
        times.chain = (t3 - t2).as_secs_f64();
        times.estimate = (t4 - t3).as_secs_f64();
        times.lift = t4.elapsed().as_secs_f64();
        Ok((self.unstack(&b), times, Estimate { error, stability, margin }))
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
