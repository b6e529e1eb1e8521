//! Marker particles from the reduced state (seed 000 §6.5, Eq. 13), the CPU f64 reference of
//! the device pass in reduced mode ([`crate::fluid::gpu::GpuParticles::new_reduced`]).
//!
//! "We never need to expand the full representation of the geometry or flux": a particle in
//! cell c evaluates the positions of c's vertices as `B_g` rows times ĝ and the fluxes through
//! c's faces as `B_f` rows times f̂, nothing else — for its velocity (Eq. 13), and for every
//! cell its walk visits. The walk's fallback, a grid hash of the cells' bounding boxes, is
//! built once, from a box per vertex holding every position the vertex takes in the model's
//! training motions (a reduced geometry that is a convex combination of training geometries
//! keeps every vertex in its box); [`ReducedParticles::covers`] says whether a reduced geometry
//! stays inside, and [`ReducedParticles::widen`] grows the boxes for one that does not.
//!
//! Everything else — Euler substeps, the mesh moving linearly across the frame, the walk
//! across faces (with the periodic translation), clamping at walls — is
//! [`crate::fluid::particles::advect_through`], shared with the full state.

use std::sync::OnceLock;

use crate::fluid::particles::{
    advect_through, AdvectReport, FrameFlux, FrameGeometry, GridHash, Particle, WalkGrid,
};
use crate::fluid::FluidError;
use crate::mesh::{Point, SimplexMesh, Topology};
use crate::tensor::{dot, RowTable};

use super::model::ReducedFluidModel;

/// A frame of the reduced state: `B_g` and the reduced geometries at the frame's start and end,
/// `B_f` and the end's reduced fluxes.
#[derive(Clone, Copy)]
pub struct ReducedFrame<'a> {
    /// `B_g` (d·vertices × m_g).
    pub b_g: &'a RowTable,
    /// ĝ at the frame's start.
    pub g0: &'a [f64],
    /// ĝ at its end.
    pub g1: &'a [f64],
    /// `B_f` (faces × m_f).
    pub b_f: &'a RowTable,
    /// f̂ of the end state.
    pub f: &'a [f64],
}

impl FrameGeometry for ReducedFrame<'_> {
    fn vertex(&self, dim: usize, v: usize) -> (Point, Point) {
        let m = self.g0.len();
        let (mut start, mut end) = ([0.0; 3], [0.0; 3]);
        for k in 0..dim {
            let row = &self.b_g.data()[(dim * v + k) * m..(dim * v + k + 1) * m];
            for ((b, a), c) in row.iter().zip(self.g0).zip(self.g1) {
                start[k] += b * a;
                end[k] += b * c;
            }
        }
        (start, end)
    }

    fn prefetch(&self, dim: usize, v: usize) {
        let m = self.g0.len();
        prefetch_rows(&self.b_g.data()[dim * v * m..(dim * v + dim) * m]);
    }
}

impl FrameFlux for ReducedFrame<'_> {
    fn flux(&self, face: usize) -> f64 {
        let m = self.f.len();
        dot(&self.b_f.data()[face * m..(face + 1) * m], self.f)
    }

    fn prefetch(&self, face: usize) {
        let m = self.f.len();
        prefetch_rows(&self.b_f.data()[face * m..(face + 1) * m]);
    }
}

/// Asks the processor to bring every cache line of `row` closer (x86-64's prefetch hint; a
/// hint only, nothing elsewhere): one request per 64 bytes from the row's start, and one for
/// its last value (the row need not start on a line).
fn prefetch_rows(row: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    for value in row.iter().step_by(8).chain(row.last()) {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: SSE is part of every x86-64 processor, and a prefetch is a hint that never
        // faults (the address is a live slice's besides).
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(value).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = row;
}

/// What reduced particles need of a model: the mesh's cells and topology, `B_g`, `B_f`, and
/// the grid hash over the training motions' vertex boxes.
pub struct ReducedParticles {
    mesh: SimplexMesh,
    topology: Topology,
    b_g: RowTable,
    b_f: RowTable,
    boxes: Vec<(Point, Point)>,
    grid: OnceLock<GridHash>,
}

impl ReducedParticles {
    /// From `model` (its mesh rebuilt from the stored cells and the mean geometry; vertex
    /// boxes over every frame of every training motion).
    pub fn new(model: &ReducedFluidModel) -> Result<Self, FluidError> {
        let (mesh, topology) = model.mesh_and_topology()?;
        let basis =
            |n: &str| model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")));
        // Copies in huge pages: particles read their rows at random (see RowTable).
        let table = |n: &str| -> Result<RowTable, FluidError> {
            RowTable::from_tensor(basis(n)?.matrix(), &format!("basis {n}"))
                .map_err(|e| FluidError::State(e.to_string()))
        };
        let (b_g, b_f) = (table("g")?, table("f")?);
        let d = model.dim;
        let inf = [f64::INFINITY; 3];
        let mut boxes = vec![(inf, inf.map(|x| -x)); mesh.vertex_count()];
        let mg = b_g.shape()[1];
        for traj in &model.trajectories {
            for g in traj.g.data().chunks(mg) {
                let frame = ReducedFrame { b_g: &b_g, g0: g, g1: g, b_f: &b_f, f: &[] };
                grow(&mut boxes, d, &frame);
            }
        }
        if boxes.first().is_some_and(|b| b.0[0] > b.1[0]) {
            return Err(FluidError::State("the model has no training motion to bound its particles".into()));
        }
        Ok(Self { mesh, topology, b_g, b_f, boxes, grid: OnceLock::new() })
    }

    /// The mesh (cells, and the model's mean geometry).
    pub fn mesh(&self) -> &SimplexMesh {
        &self.mesh
    }

    /// Its topology.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// `B_g`.
    pub fn geometry_basis(&self) -> &RowTable {
        &self.b_g
    }

    /// `B_f`.
    pub fn flux_basis(&self) -> &RowTable {
        &self.b_f
    }

    /// The walk's fallback grid, built on first use from the vertex boxes.
    pub fn grid(&self) -> &GridHash {
        self.grid.get_or_init(|| GridHash::from_vertex_boxes(&self.mesh, &self.boxes))
    }

    /// True if every vertex of the reduced geometry `g` lies in its box (so the grid hash
    /// lists every cell where it can be). Lifts the whole geometry: call it when a motion
    /// leaves its training set, not per frame.
    pub fn covers(&self, g: &[f64]) -> bool {
        let d = self.mesh.dim();
        let frame = ReducedFrame { b_g: &self.b_g, g0: g, g1: g, b_f: &self.b_f, f: &[] };
        (0..self.mesh.vertex_count()).all(|v| {
            let x = frame.vertex(d, v).0;
            let (lo, hi) = self.boxes[v];
            (0..d).all(|k| lo[k] <= x[k] && x[k] <= hi[k])
        })
    }

    /// Grows the vertex boxes to hold the reduced geometry `g` (the grid is rebuilt on its
    /// next use).
    pub fn widen(&mut self, g: &[f64]) {
        let frame = ReducedFrame { b_g: &self.b_g, g0: g, g1: g, b_f: &self.b_f, f: &[] };
        grow(&mut self.boxes, self.mesh.dim(), &frame);
        self.grid = OnceLock::new();
    }

    /// Advects `particles` through one frame of the reduced state: geometry `g0 → g1` (ĝ) and
    /// the end state's fluxes `f` (f̂); `substeps` explicit Euler steps (the seed: 10). The
    /// twin of [`crate::fluid::particles::advect_particles`] on the lifted state.
    #[allow(clippy::too_many_arguments)]
    pub fn advect(
        &self,
        g0: &[f64],
        g1: &[f64],
        f: &[f64],
        frame_time: f64,
        substeps: usize,
        particles: &mut [Particle],
    ) -> Result<AdvectReport, FluidError> {
        let (mg, mf) = (self.b_g.shape()[1], self.b_f.shape()[1]);
        if g0.len() != mg || g1.len() != mg || f.len() != mf {
            return Err(FluidError::State(format!(
                "reduced particles: ĝ of {} and {} and f̂ of {} for bases of {mg} and {mf}",
                g0.len(),
                g1.len(),
                f.len()
            )));
        }
        if let Some(bad) = particles.iter().position(|p| p.cell as usize >= self.mesh.cell_count()) {
            return Err(FluidError::State(format!(
                "particle {bad}: cell {} of a mesh of {}",
                particles[bad].cell,
                self.mesh.cell_count()
            )));
        }
        let frame = ReducedFrame { b_g: &self.b_g, g0, g1, b_f: &self.b_f, f };
        let grid = WalkGrid::Given(self.grid());
        Ok(advect_through(&self.mesh, &self.topology, &frame, &frame, grid, frame_time, substeps, particles))
    }
}

/// Grows `boxes` to hold every vertex of `frame` at its start.
fn grow(boxes: &mut [(Point, Point)], d: usize, frame: &ReducedFrame<'_>) {
    for (v, (lo, hi)) in boxes.iter_mut().enumerate() {
        let x = frame.vertex(d, v).0;
        for k in 0..d {
            lo[k] = lo[k].min(x[k]);
            hi[k] = hi[k].max(x[k]);
        }
    }
}
