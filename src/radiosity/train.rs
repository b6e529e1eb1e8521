//! Training the reduced radiosity (seed 000 §8.2, §9): sample the design space, solve the full
//! radiosity of every sample, PCA every intermediate quantity of Table 2 (streamed a block of
//! rows at a time, the pair quantities regenerated from each sample's face geometry and
//! visibility bits rather than stored), merge the bases that must agree (`B_s = B_h`,
//! `B_d = B_p`, `B_e = B_b`), premultiply every tensor of [`super::chain`] with the core, and
//! precompute the learned visibility's `B_gᵀ G` and `B_vᵀ V` (§8.3).
//!
//! The paper: 540 samples (the extremes of each axis and interior samples), 99.9 % of the
//! energy of each quantity with at most 60 vectors, one 120-vector basis for `e` and `b`.

use std::ops::Range;

use rayon::prelude::*;

use super::chain::{radiosity as radiosity_expr, stack_channels, table2_model};
use super::error::RadiosityError;
use super::form_factor::{form_factors, squared_distance, NearField};
use super::lighting::emission;
use super::mesh::{FaceGeometry, SceneMesh};
use super::reduced::{ReducedRadiosity, SkyLight};
use super::scene::{LightMode, Lights, SceneSpec};
use super::solve::{solve_jacobi, Rgb};
use super::visibility::LearnedVisibility;
use super::{JACOBI_MAX_SWEEPS, JACOBI_TOLERANCE};
use crate::reduce::{pca, Bases, Basis, ReduceError, ReduceOptions, SnapshotFn, Truncation};
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
    /// Energy fraction each PCA keeps (the paper: 0.999).
    pub energy: f64,
    /// Most vectors per quantity's basis (the paper: 60).
    pub cap: usize,
    /// Most vectors of the merged `e`/`b` basis (the paper: 120).
    pub radiosity_cap: usize,
    /// Seed of the Latin hypercube.
    pub seed: u64,
    /// Near-field treatment of the form factors.
    pub near: NearField,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            samples: 540,
            energy: 0.999,
            cap: 60,
            radiosity_cap: 120,
            seed: 1,
            near: NearField::Regularised,
        }
    }
}

fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
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
    if d <= 10 {
        for corner in 0..1u32 << d {
            push((0..d).map(|a| ranges[a][((corner >> a) & 1) as usize]).collect(), &mut out);
        }
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
}

impl Configuration {
    /// `Vis` of pair `k`.
    pub fn visible(&self, k: usize) -> bool {
        self.visibility[k / 64] >> (k % 64) & 1 == 1
    }
}

/// Solves the full radiosity of every configuration (visibility, form factors, Jacobi).
pub fn solve_configurations(
    space: &dyn DesignSpace,
    params: &[Vec<f64>],
    near: NearField,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Vec<Configuration>, RadiosityError> {
    let mut out = Vec::with_capacity(params.len());
    for (t, p) in params.iter().enumerate() {
        let mesh = space.mesh(p)?;
        let geometry = mesh.geometry();
        let f = form_factors(&mesh, near);
        let e = emission(&mesh, &geometry, space.lights(), &f);
        let (b, _) = solve_jacobi(&f, &mesh.albedo, &e, JACOBI_TOLERANCE, JACOBI_MAX_SWEEPS)?;
        // Vis(i, j) = 1 exactly where F_ij > 0 (visible pairs face each other: both scaled
        // cosines are positive).
        let mut bits = vec![0u64; f.values.len().div_ceil(64)];
        for (k, v) in f.values.iter().enumerate() {
            if *v > 0.0 {
                bits[k / 64] |= 1 << (k % 64);
            }
        }
        out.push(Configuration {
            params: p.clone(),
            g: mesh.g(),
            geometry,
            visibility: bits,
            emission: e,
            radiosity: b,
        });
        progress(t + 1);
    }
    Ok(out)
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
        let pair = |k: usize| (k / n, k % n);
        let h = |k: usize| {
            let (i, j) = pair(k);
            if i == j {
                return 0.0;
            }
            let (s, _) = super::form_factor::scaled_cosines(g, i, j);
            s / squared_distance(g, i, j, near)
        };
        let cf = |k: usize| {
            let (i, j) = pair(k);
            h(k) * h(n * j + i) / (2.0 * std::f64::consts::PI)
        };
        match self {
            Quantity::G => c.g[k],
            Quantity::N => g.normals[k / 3][k % 3],
            Quantity::A => g.normals[k].length_squared(),
            Quantity::E => c.emission[k % n][k / n],
            Quantity::B => c.radiosity[k % n][k / n],
            Quantity::S => {
                let (i, j) = pair(k);
                if i == j {
                    0.0
                } else {
                    super::form_factor::scaled_cosines(g, i, j).0
                }
            }
            Quantity::R => {
                let (i, j) = pair(k);
                if i == j {
                    0.0
                } else {
                    squared_distance(g, i, j, near)
                }
            }
            Quantity::H => h(k),
            Quantity::C => cf(k),
            Quantity::V => f64::from(u8::from(c.visible(k))),
            Quantity::D => cf(k) * f64::from(u8::from(c.visible(k))),
            Quantity::P => {
                let (i, _) = pair(k);
                cf(k) * f64::from(u8::from(c.visible(k))) / g.normals[i].length()
            }
        }
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
}

/// Progress of a training stage: (stage name, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// Trains the reduced radiosity of `space` from solved `configurations`, lit as
/// `space.lights()` says (sky lighting keeps the face–opening visibility of every
/// configuration for the run time's direct light).
pub fn train(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    progress: Progress<'_>,
) -> Result<(ReducedRadiosity, TrainingReport), RadiosityError> {
    let Some(first) = configurations.first() else {
        return Err(RadiosityError::Solve("no training configurations".into()));
    };
    let n = first.geometry.areas.len();
    let vertices = first.g.len() / 3;
    let reduce_err = |e: ReduceError| RadiosityError::Solve(e.to_string());
    let mut report = TrainingReport { bases: Vec::new(), merged: Vec::new() };
    let mut pcas: std::collections::BTreeMap<&str, Basis> = std::collections::BTreeMap::new();
    for (qi, q) in Quantity::ALL.iter().enumerate() {
        progress("pca", qi as u64, Quantity::ALL.len() as u64);
        let cap =
            if matches!(q, Quantity::E | Quantity::B) { options.radiosity_cap / 2 } else { options.cap };
        let mut source = SnapshotFn {
            dim: q.dim(n, vertices),
            count: configurations.len(),
            rows: |rows: Range<usize>| snapshot_rows(*q, configurations, rows, options.near),
        };
        let result =
            pca(q.name(), &mut source, Truncation { energy: options.energy, max_modes: cap, centred: true });
        let basis = match result {
            Ok(p) => {
                report.bases.push((
                    q.name().to_string(),
                    q.dim(n, vertices),
                    p.basis.reduced_dim(),
                    p.energy,
                ));
                p.basis
            }
            Err(e) => return Err(reduce_err(e)),
        };
        pcas.insert(q.name(), basis);
    }
    progress("pca", Quantity::ALL.len() as u64, Quantity::ALL.len() as u64);
    let merge = |name: &str, a: &str, b: &str| Basis::merge(name, &pcas[a], &pcas[b]).map_err(reduce_err);
    let mut bases = Bases::new();
    for name in ["g", "n", "r", "c", "v", "a"] {
        bases.insert(name.to_string(), pcas[name].clone());
    }
    bases.insert("sh".into(), merge("sh", "s", "h")?);
    bases.insert("dp".into(), merge("dp", "d", "p")?);
    bases.insert("b".into(), merge("b", "e", "b")?);
    for name in ["sh", "dp", "b"] {
        report.merged.push((name.to_string(), bases[name].reduced_dim()));
    }
    // Premultiply Table 2's tensors (topology and albedo: any configuration's mesh).
    let mesh = space.mesh(&first.params)?;
    let model = table2_model(&mesh, options.near, radiosity_expr());
    let premultiply_progress = |done: f64, total: f64| progress("premultiply", done as u64, total as u64);
    let mut reduced = model
        .reduce_with(
            &bases,
            &ReduceOptions { progress: Some(&premultiply_progress), ..ReduceOptions::default() },
        )
        .map_err(reduce_err)?;
    // The visibility is always given reduced (Eq. 17): its n²-row basis stays out of the model.
    reduced.forget_input_basis("v").map_err(reduce_err)?;
    // The learned visibility: B_gᵀ G and B_vᵀ V.
    let t = configurations.len();
    let (bg, bv) = (&bases["g"], &bases["v"]);
    let mut gt = vec![0.0; bg.reduced_dim() * t];
    let mut vt = vec![0.0; bv.reduced_dim() * t];
    for (c, conf) in configurations.iter().enumerate() {
        for (i, x) in bg.project(&conf.g).into_iter().enumerate() {
            gt[i * t + c] = x;
        }
        let v: Vec<f64> = (0..n * n).map(|k| f64::from(u8::from(conf.visible(k)))).collect();
        for (i, x) in bv.project(&v).into_iter().enumerate() {
            vt[i * t + c] = x;
        }
    }
    let learned = LearnedVisibility::new(
        Tensor::from_vec(&[bg.reduced_dim(), t], gt).expect("shape matches"),
        Tensor::from_vec(&[bv.reduced_dim(), t], vt).expect("shape matches"),
    )
    .map_err(|e| RadiosityError::Solve(e.to_string()))?;
    let emission_hat = bases["b"].project(&stack_channels(&first.emission));
    // Sky lighting: the face–opening visibility of every configuration, for the run time's
    // direct light.
    let sky = (space.lights().mode == LightMode::Sky).then(|| {
        let openings: Vec<u32> = (0..n as u32).filter(|&j| mesh.kind[j as usize].is_opening()).collect();
        let no = openings.len();
        let bits = configurations
            .iter()
            .map(|c| {
                let mut b = vec![0u64; (n * no).div_ceil(64)];
                for i in 0..n {
                    for (o, &j) in openings.iter().enumerate() {
                        if c.visible(n * i + j as usize) {
                            let k = i * no + o;
                            b[k / 64] |= 1 << (k % 64);
                        }
                    }
                }
                b
            })
            .collect();
        SkyLight { lights: space.lights().clone(), openings, bits, near: options.near }
    });
    Ok((ReducedRadiosity::new(reduced, learned, emission_hat, n, sky)?, report))
}
