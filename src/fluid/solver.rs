//! The full-space time step of seed 000 Fig. 2 (left), with the conventions of
//! [`super::operators`]:
//!
//! 1. induced flux `h` of the mesh motion g_t → g_{t+1} (Eq. 11, integrated exactly over the
//!    frame: the swept volume of each face divided by the frame time, so `div h = ΔV/Δt`);
//! 2. advection and diffusion of u with the relative flux `f' = f − h`:
//!    `u̇ = V⁻¹(g_t) [(A⊗f')u − V̇u + μΔu] + e`, by RK4 substeps;
//! 3. pressure projection (Eq. 10) at g_{t+1} with `D(f − h) = 0`;
//! 4. `u_{t+1} = V⁻¹(P⊗g_{t+1}) f_{t+1}`.
//!
//! **The −V̇u term.** Eq. 8 as printed, `u̇ = V⁻¹(A⊗f)u`, comes from `ṗ = (A⊗f)u` with p = Vu
//! and a constant V. On a moving mesh `d(Vu)/dt = V u̇ + V̇ u`, and the momentum balance of a
//! moving cell is `d(Vu)/dt = (A⊗f')u`. We keep the −V̇u term (V̇ = div h): with it, and f
//! divergence-free, `d/dt ½uᵀVu = uᵀ(A⊗f')u + ½uᵀV̇u = ½ Σ |u_c|² (div h)_c − ½ Σ |u_c|² V̇_c
//! = 0`, so advection is energy-neutral on moving meshes too (tested); without it a
//! compressed cell would gain kinetic energy from nothing.
//!
//! **The substep bound.** The right-hand side is `V^{-1/2} M V^{-1/2}` similar, with M's
//! symmetric part negative semidefinite, so its eigenvalues lie in the left half-plane within
//! the Gershgorin radius `ρ = max_c Σ_e |M_ce| / √(V_c V_e)`. RK4's stability region contains
//! the left half-disc of radius 2.5 (its boundary crosses the imaginary axis at 2√2 and the
//! real axis at −2.785), so each frame takes `⌈Δt ρ / 2.5⌉` substeps.

use std::time::Instant;

use rayon::prelude::*;

use crate::mesh::geometry::swept_volume;
use crate::mesh::{refuse_inverted, SimplexMesh, Topology};

use super::operators::{divergence, CellOperators};
use super::projection::{Projection, ProjectionReport};
use super::FluidError;

/// A frame's velocity after advection and diffusion, before the projection
/// ([`FluidSolver::advect`]).
pub struct Advected {
    /// The advected velocity u' (d per cell).
    pub u: Vec<f64>,
    /// The induced flux of the motion g_t → g_{t+1}, per face.
    pub h: Vec<f64>,
    /// RK4 substeps taken.
    pub substeps: usize,
    /// Seconds of the advection and diffusion (Table 1's t_a).
    pub seconds: f64,
    /// The operators at g_{t+1}.
    ops_next: CellOperators,
}

/// RK4's stable radius used for the substep count (see the module docs).
pub const RK4_RADIUS: f64 = 2.5;

/// The most RK4 substeps one frame may take (before `refine`): a frame asking for more (a
/// velocity, viscosity or frame time far beyond the mesh's scale) is refused naming the count,
/// rather than running for days.
pub const MAX_SUBSTEPS: usize = 100_000;

/// Physical parameters of a simulation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluidParams {
    /// Viscosity coefficient μ of Eq. 9 (graph-Laplacian units: volume per time).
    pub viscosity: f64,
    /// Constant body acceleration e (Eq. 5), per axis.
    pub forcing: [f64; 3],
    /// Time between frames.
    pub frame_time: f64,
}

/// The simulation state of seed 000 §5: velocities u (d per cell) and fluxes f (one per face)
/// on a mesh with geometry g.
#[derive(Clone, Debug, PartialEq)]
pub struct FluidState {
    /// The geometry vector g.
    pub g: Vec<f64>,
    /// Velocities at cell centroids, `u[d·c + k]`.
    pub u: Vec<f64>,
    /// Fluxes through faces (outward from each face's first cell).
    pub f: Vec<f64>,
}

/// What one step did and how long each stage took.
#[derive(Clone, Debug)]
pub struct StepReport {
    /// The induced fluxes h of the frame's mesh motion.
    pub h: Vec<f64>,
    /// RK4 substeps taken.
    pub substeps: usize,
    /// Seconds in advection and diffusion (t_a of Table 1).
    pub advection_seconds: f64,
    /// Seconds in the projection (t_p of Table 1).
    pub projection_seconds: f64,
    /// The projection's report.
    pub projection: ProjectionReport,
}

/// The full-space fluid solver on one topology.
#[derive(Debug)]
pub struct FluidSolver {
    mesh: SimplexMesh,
    topo: Topology,
    params: FluidParams,
    projection: Projection,
    stencil: Stencil,
    refinement: usize,
}

/// Each cell's faces, signs and neighbours flattened for the advection–diffusion rate: the
/// same operators as [`super::operators::advect`] and [`super::operators::add_laplacian`] in
/// one pass over the cells.
#[derive(Debug)]
struct Stencil {
    dim: usize,
    faces: Vec<u32>,
    signs: Vec<f64>,
    /// Neighbour per (cell, local face), `u32::MAX` across a wall.
    neighbours: Vec<u32>,
}

impl Stencil {
    fn new(topo: &Topology) -> Self {
        let d = topo.dim();
        let n = topo.cell_count() * (d + 1);
        let (mut faces, mut signs, mut neighbours) =
            (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        for c in 0..topo.cell_count() {
            for l in 0..=d {
                faces.push(topo.cell_face(c, l) as u32);
                signs.push(topo.sign(c, l));
                neighbours.push(topo.neighbour(c, l).map_or(u32::MAX, |e| e as u32));
            }
        }
        Self { dim: d, faces, signs, neighbours }
    }

    /// `out = V⁻¹[(A⊗rel)u − V̇u + μΔu] + e`, cells in parallel.
    #[allow(clippy::too_many_arguments)]
    fn rate(
        &self,
        rel: &[f64],
        vdot: &[f64],
        volumes: &[f64],
        mu: f64,
        forcing: [f64; 3],
        u: &[f64],
        out: &mut [f64],
    ) {
        let d = self.dim;
        out.par_chunks_mut(d).enumerate().for_each(|(c, o)| {
            let uc = &u[d * c..d * c + d];
            o.fill(0.0);
            for l in 0..=d {
                let s = c * (d + 1) + l;
                let flux = -0.5 * self.signs[s] * rel[self.faces[s] as usize];
                let e = self.neighbours[s];
                if e == u32::MAX {
                    for k in 0..d {
                        o[k] += flux * uc[k];
                    }
                } else {
                    let ue = &u[d * e as usize..d * e as usize + d];
                    for k in 0..d {
                        o[k] += flux * (uc[k] + ue[k]) + mu * (ue[k] - uc[k]);
                    }
                }
            }
            for k in 0..d {
                o[k] = (o[k] - vdot[c] * uc[k]) / volumes[c] + forcing[k];
            }
        });
    }
}

impl FluidSolver {
    /// A solver for `mesh` (its topology; its geometry is only the reference) with `params`.
    pub fn new(mesh: SimplexMesh, topo: Topology, params: FluidParams) -> Result<Self, FluidError> {
        if !(params.viscosity.is_finite() && params.viscosity >= 0.0) {
            return Err(FluidError::State(format!("viscosity {} must be finite and ≥ 0", params.viscosity)));
        }
        if !(params.frame_time.is_finite() && params.frame_time > 0.0) {
            return Err(FluidError::State(format!(
                "frame_time {} must be finite and > 0",
                params.frame_time
            )));
        }
        if params.forcing.iter().any(|f| !f.is_finite()) {
            return Err(FluidError::State("forcing must be finite".into()));
        }
        let projection = Projection::new(&topo)?;
        let stencil = Stencil::new(&topo);
        Ok(Self { mesh, topo, params, projection, stencil, refinement: 1 })
    }

    /// Takes `k` times the RK4 substeps the stability bound needs (at least 1): the bound keeps
    /// RK4 stable, not accurate — at `Δt ρ` near 2.5 its fastest modes have O(1) phase error —
    /// so a reference that is compared with an exact exponential (the reduced step, §7.1's
    /// study) refines it; RK4's error falls as k⁻⁴.
    pub fn with_substep_refinement(mut self, k: usize) -> Self {
        self.refinement = k.max(1);
        self
    }

    /// The mesh (topology and reference geometry).
    pub fn mesh(&self) -> &SimplexMesh {
        &self.mesh
    }

    /// The topology.
    pub fn topology(&self) -> &Topology {
        &self.topo
    }

    /// The parameters.
    pub fn params(&self) -> &FluidParams {
        &self.params
    }

    /// The projection's working memory in f64-sized entries ([`Projection::memory_len`]).
    pub fn projection_memory_len(&self) -> usize {
        self.projection.memory_len()
    }

    /// The induced fluxes of the motion g0 → g1 over one frame (Eq. 11 integrated exactly):
    /// face swept volume / frame time, oriented outward from the face's first cell.
    pub fn induced_flux(&self, g0: &[f64], g1: &[f64]) -> Vec<f64> {
        let d = self.mesh.dim();
        (0..self.topo.face_count())
            .map(|f| {
                let [c, _] = self.topo.face_cells(f);
                let l = self.topo.face_local(f)[0] as usize;
                let p0 = self.mesh.cell_points_at(g0, c as usize);
                let p1 = self.mesh.cell_points_at(g1, c as usize);
                swept_volume(d, &p0, &p1, l) / self.params.frame_time
            })
            .collect()
    }

    /// The state whose flux is the projection of velocity `u` at geometry `g` (static
    /// boundary): the divergence-free start of a simulation.
    pub fn initial_state(&mut self, g: Vec<f64>, u: &[f64]) -> Result<FluidState, FluidError> {
        self.check_len("velocity", u.len(), self.mesh.dim() * self.mesh.cell_count())?;
        self.mesh.check_coordinates(&g)?;
        let ops = CellOperators::new(&self.mesh, &self.topo, &g);
        refuse_inverted(&ops.volumes, Some(0))?;
        let zero = vec![0.0; self.topo.boundary_faces().len()];
        let (f, _) = self.projection.project(&self.topo, &ops, u, &zero, 0)?;
        let u = ops.flux_to_velocity(&self.topo, &f);
        Ok(FluidState { g, u, f })
    }

    /// Kinetic energy ½ uᵀ V(g) u (§7.1).
    pub fn energy(&self, state: &FluidState) -> f64 {
        let d = self.mesh.dim();
        let vols = self.mesh.volumes_at(&state.g);
        vols.iter()
            .enumerate()
            .map(|(c, v)| 0.5 * v * (0..d).map(|k| state.u[d * c + k].powi(2)).sum::<f64>())
            .sum()
    }

    /// One frame: the state at g_{t+1} from `state` (at g_t). `frame` names the frame in
    /// errors; an inverted g_{t+1} is refused.
    pub fn step(
        &mut self,
        state: &FluidState,
        g_next: &[f64],
        frame: usize,
    ) -> Result<(FluidState, StepReport), FluidError> {
        let advected = self.advect(state, g_next, frame)?;
        let advection_seconds = advected.seconds;
        let t1 = Instant::now();
        let h = advected.h;
        let hb: Vec<f64> = self.topo.boundary_faces().iter().map(|&f| h[f as usize]).collect();
        let (f, projection) =
            self.projection.project(&self.topo, &advected.ops_next, &advected.u, &hb, frame)?;
        let u = advected.ops_next.flux_to_velocity(&self.topo, &f);
        let projection_seconds = t1.elapsed().as_secs_f64();
        let next = FluidState { g: g_next.to_vec(), u, f };
        let substeps = advected.substeps;
        Ok((next, StepReport { h, substeps, advection_seconds, projection_seconds, projection }))
    }

    /// Stages 1–2 of a frame (see the module docs): the induced flux of g_t → g_{t+1} and the
    /// velocity advected and diffused over the frame, before the projection — what
    /// [`crate::fluid::reduced::compare`] splits a reduced step's error with.
    pub fn advect(
        &mut self,
        state: &FluidState,
        g_next: &[f64],
        frame: usize,
    ) -> Result<Advected, FluidError> {
        self.check_len("geometry", g_next.len(), self.mesh.g().len())?;
        self.mesh.check_coordinates(g_next)?;
        // The next geometry's operators (its volumes refuse an inverted frame before any work).
        let ops_next = CellOperators::new(&self.mesh, &self.topo, g_next);
        refuse_inverted(&ops_next.volumes, Some(frame))?;
        let h = self.induced_flux(&state.g, g_next);
        let t0 = Instant::now();
        let ops = CellOperators::new(&self.mesh, &self.topo, &state.g);
        let rel: Vec<f64> = state.f.iter().zip(&h).map(|(f, h)| f - h).collect();
        let vdot = divergence(&self.topo, &h);
        let substeps = self.substeps(&ops, &rel, &vdot, frame)?;
        let dt = self.params.frame_time / substeps as f64;
        let mu = self.params.viscosity;
        let forcing = self.params.forcing;
        let stencil = &self.stencil;
        let rhs = |u: &[f64], out: &mut [f64]| {
            stencil.rate(&rel, &vdot, &ops.volumes, mu, forcing, u, out);
        };
        let mut u = state.u.clone();
        let n = u.len();
        let (mut k1, mut k2, mut k3, mut k4, mut tmp) =
            (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for _ in 0..substeps {
            rhs(&u, &mut k1);
            axpy(&u, 0.5 * dt, &k1, &mut tmp);
            rhs(&tmp, &mut k2);
            axpy(&u, 0.5 * dt, &k2, &mut tmp);
            rhs(&tmp, &mut k3);
            axpy(&u, dt, &k3, &mut tmp);
            rhs(&tmp, &mut k4);
            for i in 0..n {
                u[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        if u.iter().any(|v| !v.is_finite()) {
            return Err(FluidError::State(format!(
                "frame {frame}: the velocity is not finite after advection"
            )));
        }
        Ok(Advected { u, h, substeps, seconds: t0.elapsed().as_secs_f64(), ops_next })
    }

    /// ⌈Δt ρ / 2.5⌉ with ρ the Gershgorin radius of the advection–diffusion operator, times
    /// the refinement; refused above [`MAX_SUBSTEPS`] (or for a non-finite ρ).
    fn substeps(
        &self,
        ops: &CellOperators,
        rel: &[f64],
        vdot: &[f64],
        frame: usize,
    ) -> Result<usize, FluidError> {
        let d = self.mesh.dim();
        let mu = self.params.viscosity;
        let mut rho = 0.0f64;
        for c in 0..self.mesh.cell_count() {
            let vc = ops.volumes[c];
            let mut self_term = vdot[c].abs();
            let mut row = 0.0;
            for l in 0..=d {
                let flux = 0.5 * rel[self.topo.cell_face(c, l)].abs();
                self_term += flux;
                if let Some(e) = self.topo.neighbour(c, l) {
                    self_term += mu;
                    row += (flux + mu) / (vc * ops.volumes[e]).sqrt();
                }
            }
            rho = rho.max(self_term / vc + row);
        }
        let needed = (self.params.frame_time * rho / RK4_RADIUS).ceil();
        if needed.is_nan() || needed > MAX_SUBSTEPS as f64 {
            return Err(FluidError::State(format!(
                "frame {frame}: the stability bound asks for {needed:e} RK4 substeps (at most {MAX_SUBSTEPS}): the velocity, viscosity or frame time is far beyond the mesh's scale"
            )));
        }
        Ok((needed as usize).max(1) * self.refinement)
    }

    fn check_len(&self, what: &str, got: usize, want: usize) -> Result<(), FluidError> {
        if got == want {
            Ok(())
        } else {
            Err(FluidError::State(format!("{what} has {got} entries, the mesh needs {want}")))
        }
    }
}

fn axpy(x: &[f64], a: f64, y: &[f64], out: &mut [f64]) {
    for ((o, xi), yi) in out.iter_mut().zip(x).zip(y) {
        *o = xi + a * yi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::operators::{add_laplacian, advect};
    use crate::mesh::kuhn::kuhn_box;
    use crate::mesh::Periodic;

    #[test]
    fn the_fused_rate_is_advection_plus_diffusion_over_the_volume() {
        let mesh = kuhn_box(3, [4, 2, 2], [2.0, 1.0, 1.0]).expect("box");
        let topo = Topology::new(&mesh, Some(Periodic { axis: 0 })).expect("topology");
        let stencil = Stencil::new(&topo);
        let n = 3 * mesh.cell_count();
        let u: Vec<f64> = (0..n).map(|i| ((i * 37 % 101) as f64 / 50.0) - 1.0).collect();
        let rel: Vec<f64> = (0..topo.face_count()).map(|i| ((i * 53 % 97) as f64 / 48.0) - 1.0).collect();
        let vdot: Vec<f64> = (0..mesh.cell_count()).map(|i| (i % 7) as f64 * 0.01).collect();
        let vols = mesh.volumes();
        let (mu, forcing) = (0.3, [0.1, -0.2, 0.05]);
        let mut fused = vec![0.0; n];
        stencil.rate(&rel, &vdot, &vols, mu, forcing, &u, &mut fused);
        let mut plain = vec![0.0; n];
        advect(&topo, &rel, &u, &mut plain);
        add_laplacian(&topo, &u, mu, &mut plain);
        for c in 0..mesh.cell_count() {
            for k in 0..3 {
                let want = (plain[3 * c + k] - vdot[c] * u[3 * c + k]) / vols[c] + forcing[k];
                assert!((fused[3 * c + k] - want).abs() < 1e-12, "cell {c} axis {k}");
            }
        }
    }

    #[test]
    fn a_frame_asking_for_more_substeps_than_the_cap_is_refused_naming_the_count() {
        let mesh = kuhn_box(2, [4, 2, 0], [2.0, 1.0, 1.0]).expect("box");
        let topo = Topology::new(&mesh, Some(Periodic { axis: 0 })).expect("topology");
        for (speed, viscosity) in [(1e300, 1e-3), (1.0, 1e12)] {
            let params = FluidParams { viscosity, forcing: [0.0; 3], frame_time: 0.02 };
            let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), params).expect("solver");
            let u: Vec<f64> = (0..mesh.cell_count()).flat_map(|_| [speed, 0.0]).collect();
            let state = solver.initial_state(mesh.g().to_vec(), &u).expect("state");
            let err = solver.step(&state, mesh.g(), 1).expect_err("refused").to_string();
            assert!(err.contains("frame 1") && err.contains("RK4 substeps"), "{err}");
        }
    }
}
