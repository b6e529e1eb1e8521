//! Massless marker particles (seed 000 §6.5), the CPU f64 reference of the compute pass.
//!
//! A frame's state reaches the particles through two sources: [`FrameGeometry`] gives the
//! position of one vertex at a fraction of the frame, [`FrameFlux`] the flux through one face
//! — from the full state (arrays of every vertex and face, [`FullFrame`]) or from the reduced
//! state (`B_g` rows of the vertex times ĝ, `B_f` rows of the face times f̂:
//! [`super::reduced::particles`]), so a particle only ever evaluates the vertices and faces of
//! the cells it visits.
//!
//! Each particle remembers the cell that contains it. Its velocity is the cell's, rebuilt
//! locally from the flux (Eq. 13: `u_c = (V⁻¹(g)(P⊗g)f)_c`, which touches only the cell's
//! own vertices and faces), with the frame's end state: the flux f_{t+1} and the geometry
//! g_{t+1} it belongs to (a flux means a velocity only with its own faces; evaluated on
//! other geometry a uniform flow would not stay uniform). Explicit Euler, `substeps` per
//! frame; the mesh moves linearly from g_t to g_{t+1} across the substeps, so the particle
//! is found in its cell of the moving mesh (the mesh carries particles into other cells by
//! moving under them, not by dragging them). After every substep the particle's cell is
//! found again by walking: from the remembered cell, step across the face with the most
//! negative barycentric coordinate (across the periodic boundary with the period's
//! translation) until the cell contains the particle, at most [`WALK_CAP`] steps; a walk that
//! gets lost falls back to a uniform grid hash of the cells' bounding boxes. A particle
//! pushed out of the domain through a wall (Euler's error near a curved streamline) is put
//! back at the closest point of its last cell.

use std::sync::OnceLock;

use rayon::prelude::*;

use crate::mesh::geometry::{centroid, face_centroid, signed_volume, Point};
use crate::mesh::{point_of, FaceKind, SimplexMesh, Topology};

/// Most faces a walk crosses before the grid hash takes over.
pub const WALK_CAP: usize = 64;

/// Particles a thread advects in turn (each asking for the next one's rows before it starts).
const PARTICLE_CHUNK: usize = 256;

/// A marker: position (z = 0 in 2D) and the cell containing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// Position.
    pub position: Point,
    /// The containing cell.
    pub cell: u32,
}

/// Where a frame's vertex positions come from. The geometry moves linearly across the frame:
/// at fraction `t` ∈ [0, 1] vertex `v` is at `start + t (end − start)` ([`CellCorners::at`]).
pub trait FrameGeometry: Sync {
    /// The position of vertex `v` (z = 0 in 2D) of a `dim`-dimensional mesh at the frame's
    /// start and at its end.
    fn vertex(&self, dim: usize, v: usize) -> (Point, Point);

    /// A hint that vertex `v` will be evaluated soon (a source reading rows of a basis asks
    /// the processor to fetch them); nothing by default.
    fn prefetch(&self, _dim: usize, _v: usize) {}
}

/// Where a frame's fluxes come from: the flux through face `face` (of the frame's end state).
pub trait FrameFlux: Sync {
    /// The flux through `face`.
    fn flux(&self, face: usize) -> f64;

    /// A hint that the flux through `face` will be evaluated soon; nothing by default.
    fn prefetch(&self, _face: usize) {}
}

/// A frame of the full state: the geometries at its start and end and the end's fluxes.
#[derive(Clone, Copy)]
pub struct FullFrame<'a> {
    /// Geometry at the frame's start.
    pub g0: &'a [f64],
    /// Geometry at its end.
    pub g1: &'a [f64],
    /// Fluxes of the end state.
    pub f: &'a [f64],
}

impl FrameGeometry for FullFrame<'_> {
    fn vertex(&self, dim: usize, v: usize) -> (Point, Point) {
        (point_of(dim, self.g0, v), point_of(dim, self.g1, v))
    }
}

impl FrameFlux for FullFrame<'_> {
    fn flux(&self, face: usize) -> f64 {
        self.f[face]
    }
}

/// The velocity of cell `c` from the fluxes (Eq. 13), at geometry `g`.
pub fn cell_velocity(mesh: &SimplexMesh, topo: &Topology, g: &[f64], f: &[f64], c: usize) -> Point {
    let frame = FullFrame { g0: g, g1: g, f };
    let corners = CellCorners::of(mesh, &frame, c);
    cell_velocity_at(mesh.dim(), corners.end(), topo, &frame, c)
}

/// The velocity of cell `c` (Eq. 13: `u_c = V_c⁻¹ Σ_faces σ f (x_face − x_c)`) with the cell's
/// corners `p` (the first `dim + 1` entries) and its faces' fluxes from `flux` — only those.
pub fn cell_velocity_at(d: usize, p: &[Point; 4], topo: &Topology, flux: &dyn FrameFlux, c: usize) -> Point {
    let p = &p[..=d];
    let vol = signed_volume(d, p);
    let xc = centroid(p);
    let mut u = [0.0; 3];
    for l in 0..=d {
        let xf = face_centroid(p, l);
        let flux = topo.sign(c, l) * flux.flux(topo.cell_face(c, l));
        for k in 0..d {
            u[k] += flux * (xf[k] - xc[k]) / vol;
        }
    }
    u
}

/// Barycentric coordinates of `x` in the simplex `p`: with edges `eᵢ = pᵢ − p₀` and
/// `r = x − p₀`, `λᵢ = r·gᵢ / (e₁·g₁)` for i ≥ 1, where `gᵢ` is the gradient of the simplex's
/// scaled volume with respect to `pᵢ` (in 3D `g₁ = e₂ × e₃`, `g₂ = e₃ × e₁`, `g₃ = e₁ × e₂`; in
/// 2D the edges turned), and `λ₀ = 1 − Σ λᵢ`. Twin of `simplex_barycentrics` in simplex.glsl.
pub fn barycentric(dim: usize, p: &[Point], x: Point) -> [f64; 4] {
    let sub = |a: Point, b: Point| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot3 = |a: Point, b: Point| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let r = sub(x, p[0]);
    let (e1, e2) = (sub(p[1], p[0]), sub(p[2], p[0]));
    let mut b = [0.0; 4];
    if dim == 2 {
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        b[1] = (r[0] * e2[1] - r[1] * e2[0]) / det;
        b[2] = (e1[0] * r[1] - e1[1] * r[0]) / det;
    } else {
        let cross = |a: Point, b: Point| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let e3 = sub(p[3], p[0]);
        let g = [cross(e2, e3), cross(e3, e1), cross(e1, e2)];
        let det = dot3(e1, g[0]);
        for i in 0..3 {
            b[i + 1] = dot3(r, g[i]) / det;
        }
    }
    b[0] = 1.0 - b[1..=dim].iter().sum::<f64>();
    b
}

/// Most entries per mesh cell a [`GridHash`]'s lists may hold: at about one mesh cell per
/// bucket a still cell touches up to 8 buckets; a grid whose cells' swept boxes would touch
/// more on average is made coarser, keeping it within 64 bytes (16 entries) per mesh cell (the bird's
/// training motion would otherwise list 69 million entries for its 302,679 cells, more than
/// a device binds in one storage buffer).
pub const GRID_LIST_BUDGET: usize = 16;

/// A uniform grid over the mesh's bounds listing the cells whose bounding boxes overlap
/// each grid cell: the walk's fallback.
#[derive(Clone, Debug)]
pub struct GridHash {
    lo: Point,
    size: Point,
    dims: [usize; 3],
    start: Vec<u32>,
    cells: Vec<u32>,
}

impl GridHash {
    /// About one mesh cell per grid cell; each cell listed under every bucket its bounding
    /// box touches in any of the geometries `gs` (a frame's start and end: the boxes of every
    /// geometry in between lie inside their union).
    pub fn new(mesh: &SimplexMesh, gs: &[&[f64]]) -> Self {
        let d = mesh.dim();
        let mut boxes = vec![([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]); mesh.vertex_count()];
        for g in gs {
            for (v, (lo, hi)) in boxes.iter_mut().enumerate() {
                let p = point_of(d, g, v);
                for k in 0..d {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        Self::from_vertex_boxes(mesh, &boxes)
    }

    /// Like [`Self::new`], from a box per vertex that holds every position the vertex takes
    /// (a cell then lies in the box of its vertices' boxes: a reduced model's training motions
    /// and their convex combinations).
    pub fn from_vertex_boxes(mesh: &SimplexMesh, boxes: &[(Point, Point)]) -> Self {
        let d = mesh.dim();
        let nc = mesh.cell_count();
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (a, b) in boxes {
            for k in 0..d {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        let extent: Vec<f64> = (0..d).map(|k| (hi[k] - lo[k]).max(1e-300)).collect();
        let volume: f64 = extent.iter().product();
        // Each cell's box over the motions, once.
        let cell_boxes: Vec<(Point, Point)> = (0..nc)
            .map(|c| {
                let mut b = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for &v in mesh.cell(c) {
                    let (vlo, vhi) = boxes[v as usize];
                    for k in 0..d {
                        b.0[k] = b.0[k].min(vlo[k]);
                        b.1[k] = b.1[k].max(vhi[k]);
                    }
                }
                b
            })
            .collect();
        let layout = |h: f64| {
            let mut dims = [1usize; 3];
            let mut size = [1.0; 3];
            for k in 0..d {
                dims[k] = ((extent[k] / h).ceil() as usize).clamp(1, 4096);
                size[k] = extent[k] / dims[k] as f64;
            }
            (dims, size)
        };
        let span = |dims: [usize; 3], size: Point, (mn, mx): &(Point, Point)| {
            let (mut a, mut b) = ([0usize; 3], [0usize; 3]);
            for k in 0..d {
                a[k] = (((mn[k] - lo[k]) / size[k]).floor().max(0.0) as usize).min(dims[k] - 1);
                b[k] = (((mx[k] - lo[k]) / size[k]).floor().max(0.0) as usize).min(dims[k] - 1);
            }
            (a, b)
        };
        // About one mesh cell per grid cell; coarser while the lists would exceed
        // GRID_LIST_BUDGET entries per mesh cell (cells swept far by a motion — a bird's
        // wingtips — touch many buckets).
        let mut h = (volume / nc.max(1) as f64).powf(1.0 / d as f64);
        let (dims, size) = loop {
            let (dims, size) = layout(h);
            let entries: usize = cell_boxes
                .iter()
                .map(|bx| {
                    let (a, b) = span(dims, size, bx);
                    (0..3).map(|k| b[k] - a[k] + 1).product::<usize>()
                })
                .sum();
            if entries <= GRID_LIST_BUDGET * nc.max(1) || dims.iter().all(|&n| n == 1) {
                break (dims, size);
            }
            h *= 1.25;
        };
        let total = dims[0] * dims[1] * dims[2];
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); total];
        for (c, bx) in cell_boxes.iter().enumerate() {
            let (a, b) = span(dims, size, bx);
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        lists[(z * dims[1] + y) * dims[0] + x].push(c as u32);
                    }
                }
            }
        }
        let mut start = Vec::with_capacity(total + 1);
        let mut cells = Vec::new();
        start.push(0);
        for l in lists {
            cells.extend(l);
            start.push(cells.len() as u32);
        }
        Self { lo, size, dims, start, cells }
    }

    /// The grid cell of `x`, clamped to the grid.
    pub fn bucket(&self, x: Point) -> usize {
        let mut i = [0usize; 3];
        for k in 0..3 {
            i[k] = (((x[k] - self.lo[k]) / self.size[k]).floor().max(0.0) as usize).min(self.dims[k] - 1);
        }
        (i[2] * self.dims[1] + i[1]) * self.dims[0] + i[0]
    }

    /// The mesh cells listed in bucket `b`.
    pub fn candidates(&self, b: usize) -> &[u32] {
        &self.cells[self.start[b] as usize..self.start[b + 1] as usize]
    }

    /// Grid layout for the GPU: origin, bucket size, bucket counts, CSR start and cells.
    pub fn parts(&self) -> (Point, Point, [usize; 3], &[u32], &[u32]) {
        (self.lo, self.size, self.dims, &self.start, &self.cells)
    }
}

/// Where a relocation ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Located {
    /// The walk found the cell.
    Walked,
    /// The grid hash found it.
    Hashed,
    /// Outside the domain: clamped into its last cell.
    Clamped,
}

/// Tolerance on barycentric coordinates for "inside".
const INSIDE: f64 = -1e-12;

/// A cell's corners (the first `dim + 1` entries) at a frame's start and end. The mesh moves
/// linearly across the frame, so the corners at any fraction of it are the interpolation of
/// these: a particle keeps its cell's while it stays there, and a substep evaluates no vertex
/// (on the reduced state, no `B_g` row) unless the particle changes cell.
#[derive(Clone, Copy, Debug)]
pub struct CellCorners {
    /// The cell.
    pub cell: usize,
    start: [Point; 4],
    end: [Point; 4],
}

impl CellCorners {
    /// The corners of cell `c` of `mesh` (its cells; its own geometry is not used) in `frame`.
    pub fn of(mesh: &SimplexMesh, frame: &dyn FrameGeometry, c: usize) -> Self {
        let d = mesh.dim();
        let mut out = Self { cell: c, start: [[0.0; 3]; 4], end: [[0.0; 3]; 4] };
        for (i, &v) in mesh.cell(c).iter().enumerate() {
            (out.start[i], out.end[i]) = frame.vertex(d, v as usize);
        }
        out
    }

    /// The corners at fraction `t` of the frame.
    pub fn at(&self, t: f64) -> [Point; 4] {
        let mut out = [[0.0; 3]; 4];
        for ((o, a), b) in out.iter_mut().zip(&self.start).zip(&self.end) {
            for k in 0..3 {
                o[k] = a[k] + t * (b[k] - a[k]);
            }
        }
        out
    }

    /// The corners at the frame's end.
    pub fn end(&self) -> &[Point; 4] {
        &self.end
    }
}

/// The mesh at time `t` ∈ [0, 1] of a frame whose vertices move linearly across it; only the
/// vertices of the cells a particle visits are evaluated.
#[derive(Clone, Copy)]
pub struct MovingGeometry<'a> {
    /// The topology's mesh (its cells; its own geometry is not used).
    pub mesh: &'a SimplexMesh,
    /// Where the vertices are.
    pub frame: &'a dyn FrameGeometry,
    /// Fraction of the frame.
    pub t: f64,
}

impl MovingGeometry<'_> {
    /// The corners of cell `c` at the frame's start and end.
    pub fn corners(&self, c: usize) -> CellCorners {
        CellCorners::of(self.mesh, self.frame, c)
    }

    /// The corners of cell `c` (the first `dim + 1` entries).
    pub fn points(&self, c: usize) -> [Point; 4] {
        self.corners(c).at(self.t)
    }
}

/// The grid hash a walk falls back on: built when first needed, or given.
#[derive(Clone, Copy)]
pub enum WalkGrid<'a> {
    /// Built by the function on first need, kept in the cell.
    Lazy(&'a OnceLock<GridHash>, &'a (dyn Fn() -> GridHash + Sync)),
    /// Already built.
    Given(&'a GridHash),
}

impl WalkGrid<'_> {
    fn get(&self) -> &GridHash {
        match self {
            WalkGrid::Lazy(cell, make) => cell.get_or_init(make),
            WalkGrid::Given(g) => g,
        }
    }
}

/// Finds the cell containing `particle.position` in the mesh `at`, walking from its cell; a
/// walk that reaches its cap asks the grid hash. `corners` are the corners of the particle's
/// cell on entry (evaluated if they are another cell's) and of the cell found on return.
pub fn locate(
    at: &MovingGeometry,
    topo: &Topology,
    grid: &WalkGrid,
    particle: &mut Particle,
    corners: &mut CellCorners,
) -> Located {
    let d = at.mesh.dim();
    let mut c = particle.cell as usize;
    if corners.cell != c {
        *corners = at.corners(c);
    }
    for _ in 0..WALK_CAP {
        let p = corners.at(at.t);
        let b = barycentric(d, &p[..=d], particle.position);
        let (k, worst) =
            (0..=d).map(|k| (k, b[k])).fold((0, f64::INFINITY), |m, x| if x.1 < m.1 { x } else { m });
        if worst >= INSIDE {
            particle.cell = c as u32;
            return Located::Walked;
        }
        match topo.neighbour(c, k) {
            None => {
                // Through a wall: back to the closest point of this cell.
                particle.position = clamp_into(d, &p[..=d], particle.position);
                particle.cell = c as u32;
                return Located::Clamped;
            }
            Some(e) => {
                if topo.kind(topo.cell_face(c, k)) == FaceKind::Wrap {
                    let shift = wrap_shift(at, topo, c, k, e);
                    for i in 0..d {
                        particle.position[i] += shift[i];
                    }
                }
                c = e;
                *corners = at.corners(e);
            }
        }
    }
    let grid = grid.get();
    for &cand in grid.candidates(grid.bucket(particle.position)) {
        let found = at.corners(cand as usize);
        let p = found.at(at.t);
        let b = barycentric(d, &p[..=d], particle.position);
        if (0..=d).all(|k| b[k] >= INSIDE) {
            particle.cell = cand;
            *corners = found;
            return Located::Hashed;
        }
    }
    let p = corners.at(at.t);
    particle.position = clamp_into(d, &p[..=d], particle.position);
    particle.cell = c as u32;
    Located::Clamped
}

/// The translation from cell `c`'s copy of its wrap face `k` to neighbour `e`'s copy.
pub fn wrap_shift(at: &MovingGeometry, topo: &Topology, c: usize, k: usize, e: usize) -> Point {
    let d = at.mesh.dim();
    let f = topo.cell_face(c, k);
    let [a, _] = topo.face_cells(f);
    let locals = topo.face_local(f);
    let (mine, theirs) = if a as usize == c { (locals[0], locals[1]) } else { (locals[1], locals[0]) };
    let pc = face_centroid(&at.points(c)[..=d], mine as usize);
    let pe = face_centroid(&at.points(e)[..=d], theirs as usize);
    [pe[0] - pc[0], pe[1] - pc[1], pe[2] - pc[2]]
}

/// The point of simplex `p` nearest to `x` in barycentric terms: negative weights clipped
/// and the rest renormalised (inside the cell, on the face the particle crossed).
fn clamp_into(dim: usize, p: &[Point], x: Point) -> Point {
    let b = barycentric(dim, p, x);
    let mut w: Vec<f64> = (0..=dim).map(|k| b[k].max(0.0)).collect();
    let s: f64 = w.iter().sum();
    if s <= 0.0 {
        return centroid(p);
    }
    for v in &mut w {
        *v /= s;
    }
    let mut out = [0.0; 3];
    for (k, q) in p.iter().enumerate() {
        for i in 0..3 {
            out[i] += w[k] * q[i];
        }
    }
    out
}

/// Counts of how particles were relocated during one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdvectReport {
    /// Relocations found by walking.
    pub walked: usize,
    /// Relocations the grid hash found.
    pub hashed: usize,
    /// Particles clamped back into the domain.
    pub clamped: usize,
}

/// Advects `particles` through one frame: the fluxes `f` (of the frame's end state) carry
/// them while the geometry moves from `g0` to `g1`; `substeps` explicit Euler steps of
/// `frame_time / substeps` (the seed: 10). Particles are independent: each runs its substeps
/// on its own, in parallel.
#[allow(clippy::too_many_arguments)]
pub fn advect_particles(
    mesh: &SimplexMesh,
    topo: &Topology,
    g0: &[f64],
    g1: &[f64],
    f: &[f64],
    frame_time: f64,
    substeps: usize,
    particles: &mut [Particle],
) -> AdvectReport {
    let frame = FullFrame { g0, g1, f };
    let grid = OnceLock::new();
    let make_grid = || GridHash::new(mesh, &[g0, g1]);
    advect_through(
        mesh,
        topo,
        &frame,
        &frame,
        WalkGrid::Lazy(&grid, &make_grid),
        frame_time,
        substeps,
        particles,
    )
}

/// [`advect_particles`] with the frame's vertices from `geometry` and its fluxes from `flux`
/// (full or reduced), and the walk's fallback grid from `grid`.
#[allow(clippy::too_many_arguments)]
pub fn advect_through(
    mesh: &SimplexMesh,
    topo: &Topology,
    geometry: &dyn FrameGeometry,
    flux: &dyn FrameFlux,
    grid: WalkGrid,
    frame_time: f64,
    substeps: usize,
    particles: &mut [Particle],
) -> AdvectReport {
    let d = mesh.dim();
    let substeps = substeps.max(1);
    let dt = frame_time / substeps as f64;
    // Each particle's first evaluations (its cell's corners, then the velocity from its faces'
    // fluxes) wait on memory: the next particle's are requested before this one starts.
    let prefetch = |p: &Particle| {
        let c = p.cell as usize;
        if c < mesh.cell_count() {
            for (l, &v) in mesh.cell(c).iter().enumerate() {
                geometry.prefetch(d, v as usize);
                flux.prefetch(topo.cell_face(c, l));
            }
        }
    };
    let advect_one = |p: &mut Particle, report: &mut AdvectReport| {
        // The particle's cell's corners, kept while it stays there, and the velocity of the
        // frame's end state (f belongs to g1) in that cell: evaluated again only when the
        // particle changed cell.
        let mut corners = CellCorners::of(mesh, geometry, p.cell as usize);
        let mut velocity: Option<(u32, Point)> = None;
        for s in 0..substeps {
            let u = match velocity {
                Some((cell, u)) if cell == p.cell => u,
                _ => {
                    let u = cell_velocity_at(d, corners.end(), topo, flux, p.cell as usize);
                    velocity = Some((p.cell, u));
                    u
                }
            };
            for k in 0..d {
                p.position[k] += dt * u[k];
            }
            let at = MovingGeometry { mesh, frame: geometry, t: (s + 1) as f64 / substeps as f64 };
            match locate(&at, topo, &grid, p, &mut corners) {
                Located::Walked => report.walked += 1,
                Located::Hashed => report.hashed += 1,
                Located::Clamped => report.clamped += 1,
            }
        }
    };
    particles
        .par_chunks_mut(PARTICLE_CHUNK)
        .map(|chunk| {
            let mut report = AdvectReport::default();
            for i in 0..chunk.len() {
                if let Some(next) = chunk.get(i + 1) {
                    prefetch(next);
                }
                advect_one(&mut chunk[i], &mut report);
            }
            report
        })
        .reduce(AdvectReport::default, |a, b| AdvectReport {
            walked: a.walked + b.walked,
            hashed: a.hashed + b.hashed,
            clamped: a.clamped + b.clamped,
        })
}

/// `count` particles seeded at the centroids of evenly spaced cells (deterministic).
pub fn seed_particles(mesh: &SimplexMesh, count: usize) -> Vec<Particle> {
    let nc = mesh.cell_count();
    (0..count)
        .map(|i| {
            let c = (i * nc) / count.max(1);
            Particle { position: mesh.cell_centroid(c), cell: c as u32 }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertex boxes swept across the whole domain (a motion moving every vertex far) would
    /// list every cell under every bucket; the grid coarsens to stay within its budget, and
    /// every cell is still listed under the bucket of each of its vertices.
    #[test]
    fn a_grid_of_far_swept_cells_stays_within_its_list_budget() {
        use crate::mesh::tunnel::{tunnel, TunnelSpec};
        let t = tunnel(
            &TunnelSpec { cell: 0.1, ..Default::default() },
            &crate::mesh::budget::CellBudget::machine(),
        )
        .expect("tunnel");
        let mesh = &t.mesh;
        let still: Vec<(Point, Point)> =
            (0..mesh.vertex_count()).map(|v| (mesh.point(v), mesh.point(v))).collect();
        let fine = GridHash::from_vertex_boxes(mesh, &still);
        let swept: Vec<(Point, Point)> = still
            .iter()
            .map(|&(p, _)| ([p[0] - 0.8, p[1] - 0.3, 0.0], [p[0] + 0.8, p[1] + 0.3, 0.0]))
            .collect();
        let coarse = GridHash::from_vertex_boxes(mesh, &swept);
        let nc = mesh.cell_count();
        assert!(fine.parts().4.len() <= GRID_LIST_BUDGET * nc);
        assert!(
            coarse.parts().4.len() <= GRID_LIST_BUDGET * nc,
            "{} entries for {nc} cells",
            coarse.parts().4.len()
        );
        let buckets = |g: &GridHash| g.parts().2.iter().product::<usize>();
        assert!(buckets(&coarse) < buckets(&fine), "{} vs {}", buckets(&coarse), buckets(&fine));
        for c in 0..nc {
            for &v in mesh.cell(c) {
                let b = coarse.bucket(mesh.point(v as usize));
                assert!(coarse.candidates(b).contains(&(c as u32)), "cell {c} missing under vertex {v}");
            }
        }
    }

    /// The weights against their definition — the signed volume of the simplex with `x` in
    /// place of vertex k, over the simplex's — and `Σ λₖ pₖ = x`, in 2D and 3D, for points
    /// inside and outside.
    #[test]
    fn barycentric_weights_are_volume_ratios_and_reproduce_the_point() {
        let simplices: [(usize, [Point; 4]); 2] = [
            (2, [[0.1, -0.2, 0.0], [1.3, 0.1, 0.0], [0.2, 0.9, 0.0], [0.0; 3]]),
            (3, [[0.1, -0.2, 0.05], [1.3, 0.1, -0.1], [0.2, 0.9, 0.2], [-0.1, 0.3, 1.1]]),
        ];
        for (dim, p) in simplices {
            let p = &p[..=dim];
            let vol = signed_volume(dim, p);
            for x in [[0.3, 0.2, 0.25], [2.0, -1.0, 0.5], [-0.4, 0.7, -0.3]] {
                let x = if dim == 2 { [x[0], x[1], 0.0] } else { x };
                let b = barycentric(dim, p, x);
                let mut back = [0.0; 3];
                for k in 0..=dim {
                    let mut q = p.to_vec();
                    q[k] = x;
                    let want = signed_volume(dim, &q) / vol;
                    assert!((b[k] - want).abs() < 1e-14, "{dim}D λ{k} at {x:?}: {} vs {want}", b[k]);
                    for i in 0..3 {
                        back[i] += b[k] * p[k][i];
                    }
                }
                assert!((0..3).all(|i| (back[i] - x[i]).abs() < 1e-14), "{dim}D: Σ λ p = {back:?} for {x:?}");
            }
        }
    }
}
