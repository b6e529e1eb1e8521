//! The reduced fluid model (seed 000 §6.2's table) and its file.
//!
//! The full-space tensors are exactly those the full solver evaluates ([`crate::fluid::operators`]),
//! declared in one core [`Model`] whose axes carry the basis names `u` (= p), `f`, `g`, `h`, `d`,
//! and premultiplied by the core:
//!
//! | tensor | full space | reduced |
//! |---|---|---|
//! | `A`  | advection (Eq. 6) `[u, u, f]` | `Â = B_pᵀ A ⊗₁ B_u ⊗₂ B_f` |
//! | `Ah` | advection **plus the −V̇u term** `[u, u, h]` | `Â_h = B_pᵀ (A + W) ⊗₁ B_u ⊗₂ B_h` |
//! | `L`  | graph Laplacian Δ (Eq. 9, dissipative sign) | `Δ̂ = B_uᵀ Δ B_u` |
//! | `P`  | flux to momentum `[u, f, g]` | `P̂ = B_pᵀ P ⊗₁ B_f ⊗₂ B_g` |
//! | `V`  | volume (Eq. 7) `[u, u, g, …, g]`, the g axes one symmetric group | `V̂ = B_pᵀ V ⊗₁ B_u ⊗₂…₍d+1₎ B_g` |
//! | `D`  | boundary selector `[d, f]` | `D̂ = B_dᵀ D B_f` |
//! | `Dh` | boundary selector `[d, h]` | `D̂_h = B_dᵀ D B_h` |
//! | `H`  | induced flux `[h, γ, …, γ]` ([`super::induced`]) | `Ĥ = B_hᵀ H ⊗ B_γ ⋯ ⊗ B_γ`, `B_γ = diag(B_g, B_g)` |
//!
//! `W[(c,k),(c,k),face] = σ` is `(W ⊗₂ h) u = (div h) u = V̇u`: the full solver's rate is
//! `V⁻¹[(A⊗(f − h))u − V̇u + μΔu]` (see [`crate::fluid::solver`]), so the h-axis tensor of
//! the reduced model is `A + W`, not `A` alone as §6.2 prints it. The core model's output is
//! the conversion to velocity `û = V̂(ĝ)⁻¹ (P̂ ⊗₂ ĝ) f̂` (Fig. 2, right, last line), which the
//! reduced step's fast path is tested against.
//!
//! The file is the core's safetensors model ([`ReducedModel::save_with`]) with, beside it, the
//! fluid's metadata (format, dimension, viscosity, frame time, the mesh fingerprint, the
//! training runs and thresholds, each basis's size and captured energy) and the training
//! trajectories `data/run<k>/g` and `data/run<k>/h` (frames × m: the reduced geometry and
//! induced flux of every training frame, for `--motion replay:K`) and `data/run<k>/u0`,
//! `data/run<k>/f0` (each run's reduced initial state).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::fluid::operators::{
    advection_tensor, boundary_selector_tensor, flux_to_momentum_tensor, laplacian_tensor, volume_tensor,
};
use crate::fluid::FluidError;
use crate::mesh::{SimplexMesh, Topology};
use crate::reduce::{Bases, Basis, Communicator, Expr, Model, ReduceOptions, ReducedModel, SingleRank};
use crate::tensor::{SparseTensor, Tensor};

use super::bases::{BasisReport, BasisSizes, FluidBases};
use super::cavity_motion::CavityMotion;
use super::training::TrainingSet;

/// The `extra/format` value of a reduced fluid model.
pub const FLUID_FORMAT: &str = "galerkin-reduced-fluid";
/// The reduced fluid format version this build writes and reads.
pub const FLUID_VERSION: u32 = 1;

/// A mesh's identity: dimension, counts, periodic axis and a 64-bit FNV-1a hash of its cells.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct MeshFingerprint {
    /// Spatial dimension.
    pub dim: usize,
    /// Cells.
    pub cells: usize,
    /// Faces.
    pub faces: usize,
    /// Vertices.
    pub vertices: usize,
    /// Boundary faces.
    pub boundary_faces: usize,
    /// The periodic axis.
    pub periodic_axis: Option<usize>,
    /// FNV-1a of the cells' vertex indices (hex).
    pub cells_hash: String,
}

impl MeshFingerprint {
    /// The fingerprint of a mesh's topology.
    pub fn of(mesh: &SimplexMesh, topo: &Topology, periodic_axis: Option<usize>) -> Self {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for &v in mesh.cells() {
            for b in v.to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
        Self {
            dim: mesh.dim(),
            cells: mesh.cell_count(),
            faces: topo.face_count(),
            vertices: mesh.vertex_count(),
            boundary_faces: topo.boundary_faces().len(),
            periodic_axis,
            cells_hash: format!("{h:016x}"),
        }
    }

    /// What differs between `self` and `other`, one phrase each ("cells 120 here, 96 there");
    /// empty when they are the same mesh.
    pub fn differences(&self, other: &Self) -> Vec<String> {
        let axis = |a: Option<usize>| a.map_or("none".to_string(), |a| a.to_string());
        let mut out = Vec::new();
        let mut count = |what: &str, a: usize, b: usize| {
            if a != b {
                out.push(format!("{what} {a} against {b}"));
            }
        };
        count("dimension", self.dim, other.dim);
        count("cells", self.cells, other.cells);
        count("faces", self.faces, other.faces);
        count("vertices", self.vertices, other.vertices);
        count("boundary faces", self.boundary_faces, other.boundary_faces);
        if self.periodic_axis != other.periodic_axis {
            out.push(format!(
                "periodic axis {} against {}",
                axis(self.periodic_axis),
                axis(other.periodic_axis)
            ));
        }
        if self.cells_hash != other.cells_hash && out.is_empty() {
            out.push("the same counts, but other cells (their vertex lists differ)".into());
        }
        out
    }
}

/// One line: "2D, 120 cells, 200 faces, 81 vertices, 40 boundary faces, not periodic, cells
/// 0123456789abcdef".
impl std::fmt::Display for MeshFingerprint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}D, {} cells, {} faces, {} vertices, {} boundary faces, ",
            self.dim, self.cells, self.faces, self.vertices, self.boundary_faces
        )?;
        match self.periodic_axis {
            Some(a) => write!(f, "periodic along axis {a}, ")?,
            None => write!(f, "not periodic, ")?,
        }
        write!(f, "cells hash {}", self.cells_hash)
    }
}

/// Where a model came from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The training runs' directories and frame counts.
    pub runs: Vec<(String, usize)>,
    /// The basis-size request.
    pub energy: f64,
    /// The caps asked for (`f`, `u`, `g`, `h`).
    pub caps: [Option<usize>; 4],
    /// Each basis's size and captured energy.
    pub bases: Vec<BasisReport>,
    /// The mesh the model was trained on.
    pub mesh: MeshFingerprint,
    /// The scene file it was trained from (`fluid train-scene`), with its content hash, the
    /// training's frames and runs and the engine; `None` for a model trained from snapshot
    /// directories (`fluid train`), which may come from any scene.
    #[serde(default)]
    pub source: Option<crate::reduce::provenance::Provenance>,
}

/// A mesh with its topology and periodic axis, as [`ReducedFluidModel::from_bases`] takes it.
#[derive(Clone, Copy, Debug)]
pub struct MeshOf<'a> {
    /// The mesh (its cells and a reference geometry).
    pub mesh: &'a SimplexMesh,
    /// Its topology.
    pub topology: &'a Topology,
    /// The periodic axis.
    pub periodic_axis: Option<usize>,
}

/// A reduced fluid model: the core's reduced tensors and bases, the physical parameters, the
/// provenance and the training trajectories.
#[derive(Clone, Debug)]
pub struct ReducedFluidModel {
    /// The core model (tensors `A Ah L P V D Dh`, bases `u f g h d`).
    pub core: ReducedModel,
    /// Spatial dimension.
    pub dim: usize,
    /// Viscosity μ.
    pub viscosity: f64,
    /// Time between frames.
    pub frame_time: f64,
    /// Where it came from.
    pub provenance: Provenance,
    /// Per training run: reduced geometry and induced flux per frame (frames × m_g, frames × m_h),
    /// reduced initial velocity and flux.
    pub trajectories: Vec<Trajectory>,
    /// The mesh's cells (d + 1 vertex indices each), to write lifted snapshots.
    pub cells: Vec<u32>,
    /// For the cavity: ĝ as a function of its compressions, to drive it at run time.
    pub cavity: Option<CavityMotion>,
    /// How much of each flux direction's velocity `B_u` sees, measured on training geometries
    /// ([`super::exact_projection::FluxVelocityGrams`]); the step narrows its projection by it.
    /// `None` for models trained before it was measured.
    pub flux_grams: Option<super::exact_projection::FluxVelocityGrams>,
}

/// Most training geometries [`ReducedFluidModel::train`] measures the flux velocity Gram
/// matrices on (spread evenly over the runs' frames): each costs about as much as a few full
/// steps.
pub const FLUX_GRAM_GEOMETRIES: usize = 9;

/// Up to `most` full-space geometries of `set`'s runs, spread evenly over all their frames
/// (frame 0 of the first run first), each with its run and frame named.
fn training_geometries(set: &TrainingSet, most: usize) -> Result<Vec<(String, Vec<f64>)>, FluidError> {
    let frames: Vec<(usize, usize)> = set
        .runs()
        .iter()
        .enumerate()
        .flat_map(|(r, run)| (0..run.meta().frames).map(move |k| (r, k)))
        .collect();
    let n = frames.len().min(most.max(1));
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let (r, k) = frames[i * frames.len() / n];
        let name = format!("training run {r} ({}) frame {k}", set.paths()[r].display());
        out.push((name, set.runs()[r].frame("g", k)?));
    }
    Ok(out)
}

/// One training run's reduced motion and initial state.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// ĝ per frame (frames × m_g).
    pub g: Tensor,
    /// ĥ per frame (frames × m_h; m_h = 0 without B_h).
    pub h: Tensor,
    /// û of frame 0.
    pub u0: Vec<f64>,
    /// f̂ of frame 0.
    pub f0: Vec<f64>,
}

/// The core model of the fluid's tensors on `mesh` (see the module docs); `with_h` and
/// `with_d` say whether the induced-flux and boundary tensors are declared.
/// `frame_time` scales the induced-flux tensor `H`, declared only when `with_h` and `frame_time`
/// is given.
pub fn full_model(
    mesh: &SimplexMesh,
    topo: &Topology,
    with_h: bool,
    with_d: bool,
    frame_time: Option<f64>,
) -> Model {
    let d = mesh.dim();
    let g = Expr::input("g");
    let mut v = Expr::tensor("V");
    for axis in 2..2 + d {
        v = v.times(axis, g.clone());
    }
    let p = Expr::tensor("P").times(1, Expr::input("f")).times(2, g.clone());
    let output = v.inverse().times(1, p);
    let mut v_axes = vec!["u", "u"];
    v_axes.extend(std::iter::repeat_n("g", d));
    let mut model = Model::new(output)
        .with_input("f", "f")
        .with_input("g", "g")
        .with_tensor("A", &["u", "u", "f"], advection_tensor(topo))
        .with_tensor("L", &["u", "u"], laplacian_tensor(topo))
        .with_tensor("P", &["u", "f", "g"], flux_to_momentum_tensor(mesh, topo))
        .with_tensor("V", &v_axes, volume_tensor(mesh));
    if with_h {
        model = model.with_tensor("Ah", &["u", "u", "h"], advection_with_volume_change(topo));
        if let Some(dt) = frame_time {
            let mut h_axes = vec!["h"];
            h_axes.extend(std::iter::repeat_n("gg", d));
            model = model.with_tensor("H", &h_axes, super::induced::induced_flux_tensor(mesh, topo, dt));
        }
    }
    if with_d {
        model = model.with_tensor("D", &["d", "f"], boundary_selector_tensor(topo));
        if with_h {
            model = model.with_tensor("Dh", &["d", "h"], boundary_selector_tensor(topo));
        }
    }
    model
}

/// `A + W`: advection by a flux plus the volume change it implies, `(W ⊗₂ h) u = (div h) u`
/// (the −V̇u term of [`crate::fluid::solver`], with V̇ = div h).
pub fn advection_with_volume_change(topo: &Topology) -> SparseTensor {
    let d = topo.dim();
    let mut t = advection_tensor(topo);
    for c in 0..topo.cell_count() {
        for l in 0..=d {
            let (face, sigma) = (topo.cell_face(c, l), topo.sign(c, l));
            for k in 0..d {
                t.push(&[d * c + k, d * c + k, face], sigma);
            }
        }
    }
    t
}

/// `B_γ = diag(B_g, B_g)`, the basis of the stacked geometry `[g_t; g_{t+1}]`.
fn stacked(bg: &Basis) -> Result<Basis, FluidError> {
    let (n, m) = (bg.full_dim(), bg.reduced_dim());
    let mut data = vec![0.0; 4 * n * m];
    for i in 0..n {
        for j in 0..m {
            let v = bg.matrix().data()[i * m + j];
            data[i * 2 * m + j] = v;
            data[(n + i) * 2 * m + m + j] = v;
        }
    }
    Basis::new("gg", Tensor::from_vec(&[2 * n, 2 * m], data).expect("2n × 2m"), 1e-9)
        .map_err(FluidError::from)
}

impl ReducedFluidModel {
    /// Builds the bases of `set` ([`FluidBases::build`]) and trains the model on them
    /// ([`Self::train`]); `stage(name)` is called as each stage starts. One rank:
    /// [`Self::fit_across`].
    pub fn fit(
        set: &TrainingSet,
        sizes: &BasisSizes,
        stage: &mut dyn FnMut(&str),
    ) -> Result<Self, FluidError> {
        Self::fit_across(set, sizes, stage, &SingleRank)
    }

    /// [`Self::fit`] shared over `ranks`: the PCAs and the premultiplication take each rank's
    /// share of the rows (cells, faces, vertices) and of the tensors' entries and meet in
    /// allreduces ([`crate::reduce::ranks`]); every rank returns the same model, within
    /// rounding of one rank's.
    pub fn fit_across(
        set: &TrainingSet,
        sizes: &BasisSizes,
        stage: &mut dyn FnMut(&str),
        ranks: &dyn Communicator,
    ) -> Result<Self, FluidError> {
        let bases = FluidBases::build(set, sizes, stage, ranks)?;
        Self::train(set, bases, sizes, stage, ranks)
    }

    /// Trains a model on `set` with `bases` (built by [`FluidBases::build`]): premultiplies every
    /// tensor and projects every training run's motion, then refuses the model if a training
    /// frame's `V̂(ĝ)` is not positive definite ([`Self::check_trajectories`]). `stage(name)`
    /// is called per stage.
    pub fn train(
        set: &TrainingSet,
        bases: FluidBases,
        sizes: &BasisSizes,
        stage: &mut dyn FnMut(&str),
        ranks: &dyn Communicator,
    ) -> Result<Self, FluidError> {
        stage("trajectories");
        let mut trajectories = Vec::new();
        for run in set.runs() {
            trajectories.push(project_run(run, &bases)?);
        }
        let runs = set.paths().iter().zip(set.frames()).map(|(p, k)| (p.display().to_string(), k)).collect();
        stage("premultiply");
        let mesh =
            MeshOf { mesh: set.mesh(), topology: set.topology(), periodic_axis: set.meta().periodic_axis };
        let mut model = Self::from_bases(mesh, set.params(), true, bases, sizes, runs, trajectories, ranks)?;
        model.check_trajectories()?;
        stage("flux velocities");
        model.flux_grams = Some(super::exact_projection::FluxVelocityGrams::measure(
            &model,
            &training_geometries(set, FLUX_GRAM_GEOMETRIES)?,
        )?);
        Ok(model)
    }

    /// Refuses a model under which a training frame's reduced geometry has a volume matrix
    /// `V̂(ĝ)` that is not positive definite (the reduced step could not run through it),
    /// naming the run and frame; the geometry basis may fold cells of the projected mesh
    /// ([`super::bases::ProjectedGeometry`]) as long as this holds.
    pub fn check_trajectories(&self) -> Result<(), FluidError> {
        let fluid = super::step::ReducedFluid::new(self)?;
        for (r, (trajectory, (run, _))) in self.trajectories.iter().zip(&self.provenance.runs).enumerate() {
            let mg = trajectory.g.shape()[1];
            for (frame, g) in trajectory.g.data().chunks(mg.max(1)).enumerate() {
                fluid.check_geometry(
                    g,
                    &format!("V̂(ĝ) of training run {r} ({run}) frame {frame} (keep more geometry modes: --m-g or a higher --energy)"),
                )?;
            }
        }
        Ok(())
    }

    /// Premultiplies the fluid's tensors on `mesh` by `bases` (the work of [`Self::train`]
    /// once the bases and trajectories are known; benchmarks give synthetic bases), the
    /// induced-flux tensor only if `induced` (the step does not read it; driven motions do),
    /// each rank of `ranks` premultiplying its share of every tensor's entries.
    #[allow(clippy::too_many_arguments)]
    pub fn from_bases(
        mesh: MeshOf<'_>,
        params: &crate::fluid::FluidParams,
        induced: bool,
        bases: FluidBases,
        sizes: &BasisSizes,
        runs: Vec<(String, usize)>,
        trajectories: Vec<Trajectory>,
        ranks: &dyn Communicator,
    ) -> Result<Self, FluidError> {
        let (topo, periodic_axis) = (mesh.topology, mesh.periodic_axis);
        let mesh = mesh.mesh;
        if params.forcing.iter().any(|&e| e != 0.0) {
            return Err(FluidError::State(format!(
                "the training runs have body forcing {:?}: the reduced model has no forcing term yet",
                params.forcing
            )));
        }
        let model = full_model(
            mesh,
            topo,
            bases.h.is_some(),
            bases.d.is_some(),
            induced.then_some(params.frame_time),
        );
        let mut core_bases = Bases::new();
        core_bases.insert("u".into(), bases.u.clone());
        core_bases.insert("f".into(), bases.f.clone());
        core_bases.insert("g".into(), bases.g.clone());
        if let Some(h) = &bases.h {
            core_bases.insert("h".into(), h.clone());
            if induced {
                core_bases.insert("gg".into(), stacked(&bases.g)?);
            }
        }
        if let Some(d) = &bases.d {
            core_bases.insert("d".into(), d.clone());
        }
        let options = ReduceOptions { ranks, ..ReduceOptions::default() };
        let mut core = model.reduce_with(&core_bases, &options).map_err(FluidError::from)?;
        // The core keeps the bases of inputs and outputs; the step needs B_h and B_d too.
        core.bases.extend(core_bases.into_iter().filter(|(k, _)| k == "h" || k == "d"));
        let provenance = Provenance {
            runs,
            energy: sizes.energy,
            caps: [sizes.m_f, sizes.m_u, sizes.m_g, sizes.m_h],
            bases: bases.reports.clone(),
            mesh: MeshFingerprint::of(mesh, topo, periodic_axis),
            source: None,
        };
        let out = Self {
            core,
            dim: mesh.dim(),
            viscosity: params.viscosity,
            frame_time: params.frame_time,
            provenance,
            trajectories,
            cells: mesh.cells().to_vec(),
            cavity: None,
            flux_grams: None,
        };
        out.check_shapes()?;
        Ok(out)
    }

    /// Bytes of the reduced tensors and bases (f64): the file's size, about.
    pub fn bytes(&self) -> usize {
        let bases: usize =
            ["u", "f", "g", "h", "d"].iter().filter_map(|b| self.basis(b)).map(|b| b.matrix().len()).sum();
        self.tensor_bytes() + 8 * bases
    }

    /// Bytes of the reduced tensors alone (f64): what the reduced step reads; the bases are
    /// needed only to lift a state to the full space.
    pub fn tensor_bytes(&self) -> usize {
        8 * self.core.tensors().map(|(_, _, t)| t.len()).sum::<usize>()
    }

    /// A cavity model's largest trained compression of each cavity, read back from its
    /// training trajectories' reduced geometries ([`CavityMotion::compressions_of`]); `None`
    /// for other models or where the geometry basis cannot tell.
    pub fn trained_compressions(&self) -> Option<[f64; 3]> {
        let motion = self.cavity.as_ref()?;
        let m = motion.map.shape()[0];
        motion.trained_compressions(self.trajectories.iter().flat_map(|t| t.g.data().chunks(m)))
    }

    /// A warning when the compressions `largest` go beyond what a cavity model was trained on
    /// (see [`super::cavity_motion::beyond_training`]); `None` within it or for other models.
    pub fn warn_beyond_training(&self, largest: [f64; 3]) -> Option<String> {
        super::cavity_motion::beyond_training(self.trained_compressions()?, largest)
    }

    /// A basis of the model (`u f g h d`).
    pub fn basis(&self, name: &str) -> Option<&Basis> {
        self.core.basis(name)
    }

    /// A reduced tensor of the model (`A Ah L P V D Dh`).
    pub fn tensor(&self, name: &str) -> Option<&Tensor> {
        self.core.tensor(name)
    }

    /// Reduced dimension of a basis (0 for an absent one).
    pub fn dim_of(&self, name: &str) -> usize {
        self.basis(name).map_or(0, Basis::reduced_dim)
    }

    /// The model with `B_u`, `B_f` (and `B_h`) cut to their first `m_u`, `m_f` (`m_h`)
    /// columns: every tensor is the leading block of this one's (the bases are nested PCA
    /// modes), except `B_d`, which is built again from the cut bases by constraint reduction,
    /// with `D̂` and `D̂_h`. `topo` is the model's mesh topology.
    pub fn truncated(
        &self,
        m_u: usize,
        m_f: usize,
        m_h: Option<usize>,
        topo: &Topology,
    ) -> Result<Self, FluidError> {
        let fp = &self.provenance.mesh;
        if (topo.dim(), topo.cell_count(), topo.face_count(), topo.boundary_faces().len())
            != (fp.dim, fp.cells, fp.faces, fp.boundary_faces)
        {
            return Err(FluidError::State(format!(
                "the topology given does not fit the model's mesh {fp:?}"
            )));
        }
        let mut dims = BTreeMap::new();
        dims.insert("u".to_string(), m_u);
        dims.insert("f".to_string(), m_f);
        let mh = m_h.unwrap_or(self.dim_of("h")).min(self.dim_of("h"));
        if self.dim_of("h") > 0 {
            dims.insert("h".to_string(), mh.max(1));
        }
        let mut core = self.core.truncated(&dims).map_err(FluidError::from)?;
        let (bf, bh) = (core.basis("f").cloned(), core.basis("h").cloned());
        let bf = bf.ok_or_else(|| FluidError::State("the model has no basis f".into()))?;
        core.remove("D", Some("d"));
        core.remove("Dh", None);
        if let Some(bd) = super::bases::constraint_basis(topo, &bf, bh.as_ref())? {
            let (rows, nb, k) = super::bases::boundary_rows(topo, &bf, bh.as_ref());
            let md = bd.reduced_dim();
            let block = |from: usize, to: usize| {
                let w = to - from;
                let mut out = vec![0.0; md * w];
                for i in 0..md {
                    for j in 0..w {
                        out[i * w + j] =
                            (0..nb).map(|r| bd.matrix().data()[r * md + i] * rows[r * k + from + j]).sum();
                    }
                }
                Tensor::from_vec(&[md, w], out).expect("m_d × m")
            };
            let mf = bf.reduced_dim();
            core.insert_tensor("D", &["d", "f"], block(0, mf));
            if bh.is_some() {
                core.insert_tensor("Dh", &["d", "h"], block(mf, k));
            }
            core.bases.insert("d".into(), bd);
        }
        let mut out = self.clone();
        out.core = core;
        // N depends on the whole of B_u: kept only while B_u is.
        out.flux_grams = match &self.flux_grams {
            Some(g) if m_u == self.dim_of("u") => Some(g.leading(m_f)?),
            _ => None,
        };
        let mh = out.dim_of("h");
        for t in &mut out.trajectories {
            t.h = t.h.leading(&[t.h.shape()[0], mh]).map_err(|e| FluidError::State(e.to_string()))?;
            t.u0.truncate(m_u);
            t.f0.truncate(m_f);
        }
        let cut: Vec<usize> = out.provenance.bases.iter().map(|r| out.dim_of(&r.name)).collect();
        for (r, m) in out.provenance.bases.iter_mut().zip(cut) {
            if m != r.columns {
                r.note = format!("cut from {} columns; {}", r.columns, r.note);
                r.columns = m;
            }
        }
        out.check_shapes()?;
        Ok(out)
    }

    /// The model's mesh at the first training run's first reduced geometry (lifted), and its
    /// topology.
    pub fn mesh_and_topology(&self) -> Result<(SimplexMesh, Topology), FluidError> {
        let bg = self.basis("g").ok_or_else(|| FluidError::State("the model has no basis g".into()))?;
        let g0 = self.trajectories.first().map(|t| t.g.data()[..bg.reduced_dim()].to_vec());
        let g0 = g0.ok_or_else(|| FluidError::State("the model has no training trajectory".into()))?;
        let mesh = SimplexMesh::new(self.dim, bg.lift(&g0), self.cells.clone())?;
        let axis = self.provenance.mesh.periodic_axis;
        let topo = Topology::new(&mesh, axis.map(|axis| crate::mesh::Periodic { axis }))?;
        Ok((mesh, topo))
    }

    /// The scene file to use with this model: `given` when there is one, else the scene the
    /// model was trained from (its provenance), refused when its content changed since
    /// training (naming the stored and the current SHA-256) or when the model does not name
    /// one (trained from snapshot directories).
    pub fn scene_file(&self, given: Option<&std::path::Path>) -> Result<std::path::PathBuf, FluidError> {
        if let Some(path) = given {
            return Ok(path.to_path_buf());
        }
        let Some(source) = &self.provenance.source else {
            return Err(FluidError::State(
                "the model does not name its scene (it was trained from snapshot directories by `fluid train`): give --scene FILE".into(),
            ));
        };
        let path = std::path::PathBuf::from(&source.scene);
        let now = crate::reduce::provenance::files_sha256(&[&path]).map_err(|e| {
            FluidError::State(format!(
                "the scene the model was trained from cannot be read ({e}): give --scene FILE"
            ))
        })?;
        source.check_scene(&path, &now).map_err(FluidError::State)?;
        Ok(path)
    }

    /// Refuses a mesh other than the one the model was trained on, naming both.
    pub fn check_mesh(&self, fingerprint: &MeshFingerprint) -> Result<(), FluidError> {
        if *fingerprint == self.provenance.mesh {
            Ok(())
        } else {
            Err(FluidError::State(format!(
                "not the mesh the model was trained on (model's against this: {}): trained on [{}], given [{}]",
                self.provenance.mesh.differences(fingerprint).join("; "),
                self.provenance.mesh,
                fingerprint
            )))
        }
    }
}

/// A run's reduced motion (ĝ, ĥ per frame) and initial state.
fn project_run(
    run: &crate::fluid::snapshots::SnapshotReader,
    bases: &FluidBases,
) -> Result<Trajectory, FluidError> {
    project_with(run, [&bases.u, &bases.f, &bases.g], bases.h.as_ref())
}

/// A run's frames projected into `B_u`, `B_f`, `B_g` (and `B_h`): ĝ and ĥ per frame, û and f̂ of
/// frame 0.
fn project_with(
    run: &crate::fluid::snapshots::SnapshotReader,
    [bu, bf, bg]: [&Basis; 3],
    bh: Option<&Basis>,
) -> Result<Trajectory, FluidError> {
    let frames = run.meta().frames;
    let mg = bg.reduced_dim();
    let mh = bh.map_or(0, Basis::reduced_dim);
    let mut g = Vec::with_capacity(frames * mg);
    let mut h = Vec::with_capacity(frames * mh);
    for k in 0..frames {
        g.extend(bg.project(&run.frame("g", k)?));
        if let Some(bh) = bh {
            h.extend(bh.project(&run.frame("h", k)?));
        }
    }
    Ok(Trajectory {
        g: Tensor::from_vec(&[frames, mg], g).expect("frames × m_g"),
        h: Tensor::from_vec(&[frames, mh], h).expect("frames × m_h"),
        u0: bu.project(&run.frame("u", 0)?),
        f0: bf.project(&run.frame("f", 0)?),
    })
}

/// Relative difference of frame times above which a recorded run is refused as not the
/// model's pace (both are decimal numbers written and read back, so equal ones agree to
/// rounding).
const FRAME_TIME_TOLERANCE: f64 = 1e-9;

impl Trajectory {
    /// The motion a recorded full run made — any snapshot directory of the model's mesh: a
    /// training run, a held-out obstacle, a driven cavity — projected into `model`'s bases, so
    /// the reduced model can follow exactly the geometry (and induced flux) of that run from its
    /// frame 0 (seed 000 §6.2's replayed trajectories, for a run the model never saw). Refused,
    /// naming `run`'s directory, when it is another mesh or topology (the mesh fingerprint of
    /// its frame 0), another frame time, or holds no frame after the first.
    pub fn recorded(
        model: &ReducedFluidModel,
        run: &crate::fluid::snapshots::SnapshotReader,
        dir: &std::path::Path,
    ) -> Result<Self, FluidError> {
        let (mesh, topo) = run.mesh_at(0)?;
        let fingerprint = MeshFingerprint::of(&mesh, &topo, run.meta().periodic_axis);
        model.check_mesh(&fingerprint).map_err(|e| FluidError::State(format!("{}: {e}", dir.display())))?;
        let (dt, model_dt) = (run.meta().frame_time, model.frame_time);
        let same_pace = (dt - model_dt).abs() <= FRAME_TIME_TOLERANCE * model_dt.abs();
        if !same_pace {
            return Err(FluidError::State(format!(
                "{}: frames {dt} s apart, the model steps {model_dt} s a frame (trained at that pace)",
                dir.display()
            )));
        }
        if run.meta().frames < 2 {
            return Err(FluidError::State(format!(
                "{}: the run holds its initial state only, no motion to follow",
                dir.display()
            )));
        }
        let basis =
            |n: &str| model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")));
        project_with(run, [basis("u")?, basis("f")?, basis("g")?], model.basis("h"))
    }

    /// Frames of motion after the initial state.
    pub fn frames(&self) -> usize {
        self.g.shape()[0].saturating_sub(1)
    }
}
