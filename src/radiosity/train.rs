//! Training the reduced radiosity (seed 000 §8.2, §9): sample the design space, solve the full
//! radiosity of every sample, PCA every intermediate quantity of Table 2, merge the bases that
//! must agree (`B_s = B_h`, `B_d = B_p`, `B_e = B_b`), premultiply every tensor of
//! [`super::chain`] with the core, precompute the learned visibility's `B_gᵀ G` and
//! `B_vᵀ V` (§8.3), and correct the reduced operator at every training configuration
//! ([`super::operator_correction`]).
//!
//! Nothing of size `n²` is ever held: the pair quantities are regenerated a block of pairs at a
//! time from each sample's face geometry and visibility bits ([`super::snapshots`]); their PCA
//! bases are kept as snapshot coefficients ([`crate::reduce::SnapshotBasis`]) — one pass over
//! the pairs for the Gram matrices, one to orthonormalise and merge the modes — and the pair
//! tensors are premultiplied chunk by chunk against basis rows regenerated on demand. The
//! per-face quantities (`g`, `n`, `a`, `e`, `b`) use the stored PCA.
//!
//! The paper: 540 samples (the extremes of each axis and interior samples), 99.9 % of the
//! energy of each quantity with at most 60 vectors, one 120-vector basis for `e` and `b`.

use std::ops::Range;
use std::sync::Arc;

use rayon::prelude::*;

use super::error::RadiosityError;
use super::form_factor::{form_factors, NearField};
use super::lighting::emission;
use super::mesh::{FaceGeometry, SceneMesh};
use super::near_correction::{apply, near_corrections, NearCorrection};
use super::operator_correction::CorrectionReport;
use super::reduced::ReducedRadiosity;
use super::scene::{LightMode, Lights, SceneSpec};
use super::snapshots::{pair_values, PAIR_QUANTITIES};
use super::solve::{solve_jacobi, Rgb};
use super::train_stages::{assemble, basis_parts, correction, premultiplied};
use super::{JACOBI_MAX_SWEEPS, JACOBI_TOLERANCE};
use crate::reduce::effectivity::splitmix;
use crate::reduce::{Communicator, SingleRank};
use crate::tensor::Tensor;

/// A family of meshes of one topology over a box of design parameters.
pub trait DesignSpace: Sync {
    /// `[lo, hi]` per parameter.
    fn ranges(&self) -> Vec<[f64; 2]>;
    /// The default parameters.
    fn defaults(&self) -> Vec<f64>;
    /// The mesh at `p` (same faces for every `p`).
    fn mesh(&self, p: &[f64]) -> Result<SceneMesh, RadiosityError>;
    /// The lights.
    fn lights(&self) -> &Lights;
}

impl DesignSpace for SceneSpec {
    fn ranges(&self) -> Vec<[f64; 2]> {
        SceneSpec::ranges(self).to_vec()
    }
    fn defaults(&self) -> Vec<f64> {
        SceneSpec::defaults(self).to_vec()
    }
    fn mesh(&self, p: &[f64]) -> Result<SceneMesh, RadiosityError> {
        let p: [f64; 4] = p.try_into().map_err(|_| RadiosityError::Parameter {
            name: "parameters".into(),
            message: format!("{} values for 4 parameters", p.len()),
        })?;
        self.check(&p)?;
        super::architecture::build(self, &p)
    }
    fn lights(&self) -> &Lights {
        &self.lights
    }
}

/// How to train.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainOptions {
    /// Number of sampled configurations (the paper: 540).
    pub samples: usize,
    /// Energy fraction each PCA keeps (the paper: 0.999), except the geometry's.
    pub energy: f64,
    /// Energy fraction the geometry basis `B_g` keeps: by default every mode above rounding
    /// (1 − 1e-12). A scene's vertices vary in a few modes (the two rooms: about
    /// `[1, w, s, d, tan θ, s·tan θ, d·tan θ]` — 7 modes on 16 samples, 8 on the default 540;
    /// an OBJ scene: one per target), so this basis is exact (every configuration's vertices
    /// back to 1e-13 m) and still small, while the paper's 0.999 kept 5 and lost centimetres of
    /// vertex displacement before any tensor was reduced.
    pub geometry_energy: f64,
    /// Energy fraction the squared distances' basis `B_r` keeps; `None`: [`Self::energy`].
    /// By default every mode above rounding, as for `g`: `r = R ⊗₁ g ⊗₂ g` is a quadratic
    /// form of the geometry, so it lies in the span of the products of `B_g`'s modes (at most
    /// `m_g (m_g + 1) / 2` vectors) and the basis stays small while exact. Truncated (the
    /// paper's 0.999 keeps 6), the lifted `r` is not positive at the nearest pairs, and the
    /// reduced diagonal `H ⊗₂ r` that the chain inverts for the half form factors loses its
    /// definiteness: on the 4,876-face scene an eigenvalue of −3.9·10⁻³ against 60 at the
    /// top, and the chain's operator 18× off the exact one at that training configuration.
    pub squared_distance_energy: Option<f64>,
    /// Energy fraction the emission and radiosity bases (`B_e`, `B_b`, merged) keep; `None`:
    /// [`Self::energy`]. By default 0.9999 (the paper: 0.999 like every quantity): with the
    /// operator correction the radiosity basis limits the error, and on the 496-face scene
    /// 0.9999 (20 vectors instead of 8) took the receiving surfaces from 0.80 % to 0.59 %
    /// (mean over both sequences) at no measurable cost per reduced frame.
    pub radiosity_energy: Option<f64>,
    /// Most vectors per quantity's basis (the paper: 60).
    pub cap: usize,
    /// Most vectors of the merged `e`/`b` basis (the paper: 120).
    pub radiosity_cap: usize,
    /// Seed of the Latin hypercube.
    pub seed: u64,
    /// Near-field treatment of the chain's centroid form factors.
    pub near: NearField,
    /// The exact near field in the training solves ([`super::near_correction`]): exact
    /// polygon form factors for visible pairs within this many face diameters, carried into
    /// the model by the operator correction; by default [`super::near_field::DEFAULT_REACH`].
    /// `None`: centroid form factors only (Table 2 as printed, about 20 % low on the receiving
    /// surfaces of the 496-face scene; the only choice with sky lighting).
    pub near_correction: Option<f64>,
    /// The reduced operator corrected at the training configurations
    /// ([`super::operator_correction`]: `Q̂`, blended by Eq. 17's weights; on by default).
    /// Off: Table 2's chain alone, which cannot carry the exact near field.
    pub operator_correction: bool,
    /// The error estimate's offline part ([`super::estimate`]: every sample evaluated with
    /// itself left out of Eq. 17; on by default).
    pub estimate: bool,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            samples: 540,
            energy: 0.999,
            geometry_energy: 1.0 - 1e-12,
            squared_distance_energy: Some(1.0 - 1e-12),
            radiosity_energy: Some(0.9999),
            cap: 60,
            radiosity_cap: 120,
            seed: 1,
            near: NearField::Regularised,
            near_correction: Some(super::near_field::DEFAULT_REACH),
            operator_correction: true,
            estimate: true,
        }
    }
}

/// Most parameters whose box corners are sampled and measured (2¹⁰ corners).
pub const MAX_CORNER_PARAMETERS: usize = 10;

/// Every corner of the box `ranges` (parameter `a` at its low end where bit `a` of the corner's
/// index is 0), or none beyond [`MAX_CORNER_PARAMETERS`] parameters.
pub fn box_corners(ranges: &[[f64; 2]]) -> Vec<Vec<f64>> {
    let d = ranges.len();
    if d > MAX_CORNER_PARAMETERS {
        return Vec::new();
    }
    (0..1u32 << d).map(|corner| (0..d).map(|a| ranges[a][((corner >> a) & 1) as usize]).collect()).collect()
}

/// The training configurations: every axis's two extremes (the others at their defaults),
/// every corner of the box (up to 10 parameters), then a Latin hypercube for the rest.
pub fn sample_parameters(ranges: &[[f64; 2]], defaults: &[f64], samples: usize, seed: u64) -> Vec<Vec<f64>> {
    let d = ranges.len();
    let mut out: Vec<Vec<f64>> = Vec::new();
    let push = |p: Vec<f64>, out: &mut Vec<Vec<f64>>| {
        if out.len() < samples && !out.contains(&p) {
            out.push(p);
        }
    };
    for (a, range) in ranges.iter().enumerate() {
        for &end in range {
            let mut p = defaults.to_vec();
            p[a] = end;
            push(p, &mut out);
        }
    }
    for corner in box_corners(ranges) {
        push(corner, &mut out);
    }
    let rest = samples.saturating_sub(out.len());
    let mut state = seed;
    let strata: Vec<Vec<usize>> = (0..d)
        .map(|_| {
            let mut s: Vec<usize> = (0..rest).collect();
            for i in (1..rest).rev() {
                let j = (splitmix(&mut state) * (i + 1) as f64) as usize;
                s.swap(i, j.min(i));
            }
            s
        })
        .collect();
    for i in 0..rest {
        let p = strata
            .iter()
            .zip(ranges)
            .map(|(stratum, range)| {
                let u = (stratum[i] as f64 + splitmix(&mut state)) / rest as f64;
                range[0] + u * (range[1] - range[0])
            })
            .collect();
        push(p, &mut out);
    }
    out
}

/// One solved training configuration.
#[derive(Clone, Debug)]
pub struct Configuration {
    /// Its parameters.
    pub params: Vec<f64>,
    /// Vertex positions `g`.
    pub g: Vec<f64>,
    /// Face geometry.
    pub geometry: FaceGeometry,
    /// `Vis(i, j)` at bit `k = n·i + j`.
    pub visibility: Vec<u64>,
    /// Emission `e`.
    pub emission: Vec<Rgb>,
    /// Radiosity `b`.
    pub radiosity: Vec<Rgb>,
    /// The exact near field's correction to the centroid form factors (empty without one).
    pub near_correction: NearCorrection,
}

impl Configuration {
    /// `Vis` of pair `k`.
    pub fn visible(&self, k: usize) -> bool {
        self.visibility[k / 64] >> (k % 64) & 1 == 1
    }
}

/// Solves the full radiosity of every configuration (visibility, form factors, Jacobi), the
/// configurations themselves in parallel (about one per core): one solve alone has
/// single-threaded stretches (the mesh, parts of the Jacobi sweeps) that left a core idle a
/// third of the time. `progress` is called with the number solved so far.
pub fn solve_configurations(
    space: &dyn DesignSpace,
    params: &[Vec<f64>],
    options: &TrainOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Configuration>, RadiosityError> {
    let solved = std::sync::atomic::AtomicUsize::new(0);
    params
        .par_iter()
        .with_max_len(1)
        .map(|p| {
            let configuration = solve_configuration(space, p, options)?;
            progress(solved.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
            Ok(configuration)
        })
        .collect()
}

/// The full radiosity of the configuration at `p`, with what training keeps of it: centroid
/// form factors under `options.near`, corrected by the exact near field if
/// `options.near_correction` asks.
fn solve_configuration(
    space: &dyn DesignSpace,
    p: &[f64],
    options: &TrainOptions,
) -> Result<Configuration, RadiosityError> {
    let mesh = space.mesh(p)?;
    let geometry = mesh.geometry();
    let mut f = form_factors(&mesh, options.near);
    // Vis(i, j) = 1 exactly where the centroid F_ij > 0 (visible pairs face each other: both
    // scaled cosines are positive).
    let mut bits = vec![0u64; f.values.len().div_ceil(64)];
    bits.par_iter_mut().zip(f.values.par_chunks(64)).for_each(|(word, values)| {
        for (bit, v) in values.iter().enumerate() {
            if *v > 0.0 {
                *word |= 1 << bit;
            }
        }
    });
    let correction: NearCorrection = match options.near_correction {
        Some(reach) => near_corrections(&|i| mesh.corners(i), &geometry, &f, reach).into(),
        None => Arc::from(Vec::new()),
    };
    apply(&mut f, &correction, &geometry.areas);
    let e = emission(&mesh, &geometry, space.lights(), &f);
    let (b, _) = solve_jacobi(&f, &mesh.albedo, &e, JACOBI_TOLERANCE, JACOBI_MAX_SWEEPS)?;
    Ok(Configuration {
        params: p.to_vec(),
        g: mesh.g(),
        geometry,
        visibility: bits,
        emission: e,
        radiosity: b,
        near_correction: correction,
    })
}

/// The intermediate quantities of Table 2 whose snapshots are analysed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// Geometry `g` (3V).
    G,
    /// Normals `n` (3n).
    N,
    /// Scaled cosines `s` (n²).
    S,
    /// Squared distances `r` (n²).
    R,
    /// Half form factors `h` (n²).
    H,
    /// Visibility-free form factors `c` (n²).
    C,
    /// Visibility `v` (n²).
    V,
    /// Area-free form factors `d` (n²).
    D,
    /// Squared areas `a` (n).
    A,
    /// Form factors `p` (n²).
    P,
    /// Emission `e` (3n, channels stacked).
    E,
    /// Radiosity `b` (3n, channels stacked).
    B,
}

impl Quantity {
    /// Every quantity, in Table 2's order.
    pub const ALL: [Quantity; 12] = [
        Quantity::G,
        Quantity::N,
        Quantity::S,
        Quantity::R,
        Quantity::H,
        Quantity::C,
        Quantity::V,
        Quantity::D,
        Quantity::A,
        Quantity::P,
        Quantity::E,
        Quantity::B,
    ];

    /// Its name in Table 2.
    pub fn name(self) -> &'static str {
        ["g", "n", "s", "r", "h", "c", "v", "d", "a", "p", "e", "b"][self as usize]
    }

    /// Its full dimension for `n` faces and `vertices` vertices.
    pub fn dim(self, n: usize, vertices: usize) -> usize {
        match self {
            Quantity::G => 3 * vertices,
            Quantity::N | Quantity::E | Quantity::B => 3 * n,
            Quantity::A => n,
            _ => n * n,
        }
    }

    /// Component `k` of the quantity in configuration `c` (`near` as in training).
    pub fn value(self, c: &Configuration, k: usize, near: NearField) -> f64 {
        let g = &c.geometry;
        let n = g.areas.len();
        match self {
            Quantity::G => c.g[k],
            Quantity::N => g.normals[k / 3][k % 3],
            Quantity::A => g.normals[k].length_squared(),
            Quantity::E => c.emission[k % n][k / n],
            Quantity::B => c.radiosity[k % n][k / n],
            pair => {
                let slot =
                    PAIR_QUANTITIES.iter().position(|&q| q == pair).expect("the rest are pair quantities");
                pair_values(c, k / n, k % n, near)[slot]
            }
        }
    }

    /// Whether it lives on pairs of faces (`n²` values).
    pub fn is_pair(self) -> bool {
        PAIR_QUANTITIES.contains(&self)
    }
}

/// Rows `rows` of every configuration's snapshot of `q`, as a `rows × T` tensor.
pub fn snapshot_rows(
    q: Quantity,
    configurations: &[Configuration],
    rows: Range<usize>,
    near: NearField,
) -> Tensor {
    let t = configurations.len();
    let data: Vec<f64> = rows
        .clone()
        .into_par_iter()
        .flat_map_iter(|k| configurations.iter().map(move |c| q.value(c, k, near)))
        .collect();
    Tensor::from_vec(&[rows.len(), t], data).expect("shape matches")
}

/// What training made, besides the model: the PCA of each quantity.
#[derive(Clone, Debug)]
pub struct TrainingReport {
    /// Per quantity: name, full dimension, vectors kept, energy kept.
    pub bases: Vec<(String, usize, usize, f64)>,
    /// Merged bases: name and vectors.
    pub merged: Vec<(String, usize)>,
    /// The chain's operator against the exact projection at the training configurations, with
    /// the operator correction (`None` without it).
    pub correction: Option<CorrectionReport>,
}

/// Progress of a training stage: (stage name, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// Trains the reduced radiosity of `space` from solved `configurations`, lit as
/// `space.lights()` says (sky lighting keeps the face–opening visibility of every
/// configuration for the run time's direct light). One rank: [`train_across`].
pub fn train(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    progress: Progress<'_>,
) -> Result<(ReducedRadiosity, TrainingReport), RadiosityError> {
    train_across(space, configurations, options, progress, &SingleRank)
}

/// [`train`] shared over `ranks` (every rank holds every configuration,
/// [`super::train_ranks::solve_configurations_across`]): the Gram matrices of the pair
/// quantities and of their modes, the per-face PCAs and the premultiplication each take the
/// rank's share of rows or chunks and meet in one allreduce ([`crate::reduce::ranks`]); every
/// rank returns the same model, within rounding of one rank's.
pub fn train_across(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    progress: Progress<'_>,
    ranks: &dyn Communicator,
) -> Result<(ReducedRadiosity, TrainingReport), RadiosityError> {
    if configurations.is_empty() {
        return Err(RadiosityError::Solve("no training configurations".into()));
    }
    options.check()?;
    options.check_lights(space.lights().mode)?;
    let parts = basis_parts(configurations, options, progress, ranks)?;
    let tensors = premultiplied(space, configurations, options, &parts, progress, ranks)?;
    let mut report = TrainingReport { bases: parts.report, merged: tensors.merged.clone(), correction: None };
    let q = if options.operator_correction {
        let (q, found) = correction(space, configurations, options, &tensors, progress, ranks)?;
        report.correction = Some(found);
        Some(q)
    } else {
        None
    };
    Ok((assemble(space, configurations, options, tensors, q)?, report))
}

impl TrainOptions {
    /// Refuses the exact near field with sky lighting, whose direct light is computed outside
    /// the model with centroid form factors.
    pub fn check_lights(&self, mode: LightMode) -> Result<(), RadiosityError> {
        if self.near_correction.is_some() && mode == LightMode::Sky {
            return Err(RadiosityError::Solve(
                "the exact near field is not available with sky lighting (its direct light is \
                 computed outside the model with centroid form factors): train with the centroid \
                 near field"
                    .into(),
            ));
        }
        Ok(())
    }

    /// Refuses options no training can use: an energy fraction outside (0, 1], a cap of 0,
    /// fewer than 2 samples, the exact near field without the operator correction (the chain
    /// alone computes centroid form factors).
    pub fn check(&self) -> Result<(), RadiosityError> {
        if self.near_correction.is_some() && !self.operator_correction {
            return Err(RadiosityError::Mesh(
                "the exact near field enters the model through the operator correction: train \
                 without it only with the centroid near field"
                    .into(),
            ));
        }
        let energy_ok = |e: f64| e > 0.0 && e <= 1.0;
        if !energy_ok(self.energy)
            || !energy_ok(self.geometry_energy)
            || !self.radiosity_energy.is_none_or(energy_ok)
            || !self.squared_distance_energy.is_none_or(energy_ok)
        {
            return Err(RadiosityError::Mesh("the energy fraction must be in (0, 1]".into()));
        }
        if self.cap == 0 || self.radiosity_cap == 0 {
            return Err(RadiosityError::Mesh("the basis cap must be at least 1".into()));
        }
        if self.near_correction.is_some_and(|r| !(r.is_finite() && r > 0.0)) {
            return Err(RadiosityError::Mesh(
                "the near field's reach must be a positive number of face diameters".into(),
            ));
        }
        if self.samples < 2 {
            return Err(RadiosityError::Mesh("training needs at least 2 samples".into()));
        }
        Ok(())
    }
}
