//! Isosurface stuffing (Labelle & Shewchuk 2007): tetrahedral meshes of a domain given by a
//! signed distance function, from the body-centred cubic (BCC) lattice.
//!
//! 1. The lattice: "black" points on the grid of spacing h and "red" points at the cube
//!    centres. Its tetrahedra are the four around each red–red edge (two neighbouring cube
//!    centres) through the shared square face: each has one red–red and one black–black
//!    *long* edge (length h) and four *short* red–black edges (√3 h / 2).
//! 2. Every lattice point is labelled by the sign of −SDF (positive inside); each edge with
//!    a positive and a negative end gets a *cut point* on the surface (the SDF's root on the
//!    edge, by bisection).
//! 3. Warping: a lattice point closer than α·|e| to a cut point on one of its edges e (α =
//!    0.24999 for long edges, 0.41189 for short ones, the paper's values for its angle
//!    bounds) moves to the closest such cut point and becomes zero; cut points on its edges
//!    disappear.
//! 4. Filling: each lattice tetrahedron with a positive vertex contributes the part of it on
//!    the inside, by stencils: the whole tetrahedron (no negative vertex), one tetrahedron
//!    (one positive vertex), a pyramid (two positive, one zero, one negative: two
//!    tetrahedra) or a triangular prism (two positive and two negative, or three positive
//!    and one negative: three tetrahedra).
//!
//! Quadrilateral faces of pyramids and prisms are shared with the neighbouring lattice
//! tetrahedron and must be split the same way on both sides. We split every quadrilateral by
//! the diagonal through its vertex of smallest global index (lattice points before cut
//! points) — Dompierre et al.'s rule, which is consistent between neighbours and always
//! admits the prism's 3-tetrahedron split. The paper instead uses its parity rule; the
//! dihedral angles this gives are measured by the tests (see there) rather than assumed.

use std::collections::HashMap;

use super::budget::CellBudget;
use super::geometry::{face_area_normal, signed_volume, Point};
use super::sdf::Sdf;
use super::{MeshError, SimplexMesh};

/// Warping threshold on long (axis-parallel) lattice edges.
pub const ALPHA_LONG: f64 = 0.24999;
/// Warping threshold on short (diagonal) lattice edges.
pub const ALPHA_SHORT: f64 = 0.41189;

/// A stuffed mesh and which of its vertices lie on the surface.
#[derive(Clone, Debug)]
pub struct Stuffed {
    /// The tetrahedral mesh.
    pub mesh: SimplexMesh,
    /// Vertices on the isosurface (cut points and warped lattice points).
    pub surface: Vec<u32>,
    /// Lattice tetrahedra dropped because their stencil part was flat (all vertices on the
    /// surface, in one plane).
    pub dropped_flat: usize,
}

struct Lattice {
    n: [usize; 3],
    h: f64,
    origin: [f64; 3],
}

impl Lattice {
    fn black_count(&self) -> usize {
        (self.n[0] + 1) * (self.n[1] + 1) * (self.n[2] + 1)
    }
    fn black(&self, i: usize, j: usize, k: usize) -> usize {
        (k * (self.n[1] + 1) + j) * (self.n[0] + 1) + i
    }
    fn red(&self, i: usize, j: usize, k: usize) -> usize {
        self.black_count() + (k * self.n[1] + j) * self.n[0] + i
    }
    fn count(&self) -> usize {
        self.black_count() + self.n[0] * self.n[1] * self.n[2]
    }
    fn position(&self, v: usize) -> Point {
        let nb = self.black_count();
        let (idx, off, dims) = if v < nb {
            (v, 0.0, [self.n[0] + 1, self.n[1] + 1])
        } else {
            (v - nb, 0.5, [self.n[0], self.n[1]])
        };
        let i = idx % dims[0];
        let j = (idx / dims[0]) % dims[1];
        let k = idx / (dims[0] * dims[1]);
        [
            self.origin[0] + (i as f64 + off) * self.h,
            self.origin[1] + (j as f64 + off) * self.h,
            self.origin[2] + (k as f64 + off) * self.h,
        ]
    }
}

/// The root of `sdf` on the segment a–b, where it changes sign (bisection to 1e-12 of the
/// segment).
fn cut_point(sdf: &dyn Sdf, a: Point, b: Point) -> Point {
    let at = |t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
    let (mut lo, mut hi) = (0.0, 1.0);
    let sa = sdf.distance(a) < 0.0;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if (sdf.distance(at(mid)) < 0.0) == sa {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    at(0.5 * (lo + hi))
}

fn dist(a: Point, b: Point) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Tetrahedra a lattice cell of the domain becomes at most, about (measured: the bird in a
/// 6.2 × 6 × 4.8 box at spacing 0.1 gave 2,179,370 cells from 219,648 lattice cells, nearly all
/// of them inside).
pub const CELLS_PER_LATTICE_CELL: f64 = 10.0;

/// Sample points per axis of the coarse grid [`stuff`] estimates the domain's share of its box
/// on (20³ distance evaluations, milliseconds even for a mesh surface's distance).
const ESTIMATE_SAMPLES: usize = 20;

/// The share of the box `lo`–`hi` that the inside of `sdf` may reach: the fraction of the
/// cells of a coarse `samples`³ grid whose centre lies within half the cell's diagonal of the
/// inside. An upper bound for exact distances and for the lower bounds CSG distances give
/// (a cell the domain touches always counts), so a thin tube is never missed.
fn touched_fraction(sdf: &dyn Sdf, lo: Point, hi: Point, samples: [usize; 3]) -> f64 {
    let size: [f64; 3] = std::array::from_fn(|k| (hi[k] - lo[k]) / samples[k] as f64);
    let reach = 0.5 * dist([0.0; 3], size);
    let mut touched = 0usize;
    for k in 0..samples[2] {
        for j in 0..samples[1] {
            for i in 0..samples[0] {
                let centre = [
                    lo[0] + (i as f64 + 0.5) * size[0],
                    lo[1] + (j as f64 + 0.5) * size[1],
                    lo[2] + (k as f64 + 0.5) * size[2],
                ];
                // NaN distances count as touched: never an under-estimate.
                let d = sdf.distance(centre);
                if d < reach || d.is_nan() {
                    touched += 1;
                }
            }
        }
    }
    touched as f64 / samples.iter().product::<usize>() as f64
}

/// About how many cells [`stuff`] makes of `sdf` at spacing `h`, from above:
/// [`CELLS_PER_LATTICE_CELL`] for each lattice cell of the share of the box the domain reaches
/// (sampled on a coarse grid, at most 20³ distance evaluations).
pub fn cell_estimate(sdf: &dyn Sdf, h: f64) -> f64 {
    let (lo, hi) = sdf.bounds();
    let per_axis: [f64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / h).ceil() + 4.0);
    let samples = per_axis.map(|c| (c as usize).clamp(1, ESTIMATE_SAMPLES));
    CELLS_PER_LATTICE_CELL * per_axis.iter().product::<f64>() * touched_fraction(sdf, lo, hi, samples)
}

/// Stuffs the inside of `sdf` with tetrahedra of lattice spacing `h`. Refused before anything
/// is built: more than 6·10⁷ lattice cells, or more cells than `budget` allows by
/// [`cell_estimate`].
pub fn stuff(sdf: &dyn Sdf, h: f64, budget: &CellBudget) -> Result<Stuffed, MeshError> {
    let (lo, hi) = sdf.bounds();
    if !(h.is_finite() && h > 0.0) || lo.iter().chain(&hi).any(|v| !v.is_finite()) {
        return Err(MeshError::Generation(format!(
            "isosurface stuffing: spacing {h} or bounds not finite and positive"
        )));
    }
    let origin = lo.map(|v| v - 2.0 * h);
    // Counted in f64: a tiny spacing must be refused, not overflow the product.
    let per_axis: [f64; 3] = std::array::from_fn(|k| ((hi[k] - lo[k]) / h).ceil() + 4.0);
    if per_axis.iter().product::<f64>() > 60_000_000.0 {
        return Err(MeshError::Generation(format!(
            "isosurface stuffing: {per_axis:?} lattice cells (at most 60,000,000): raise the spacing"
        )));
    }
    // A stuffed mesh is what the fluid solver simulates; refuse one past the budget (by default
    // what the machine's memory can simulate) before building it (building it alone can
    // exhaust memory too).
    if CELLS_PER_LATTICE_CELL * per_axis.iter().product::<f64>() > budget.max_cells() {
        budget.check(&format!("isosurface stuffing at spacing {h}"), cell_estimate(sdf, h), "the spacing")?;
    }
    let n: [usize; 3] = per_axis.map(|c| c as usize);
    let lattice = Lattice { n, h, origin };
    let nl = lattice.count();
    let mut position: Vec<Point> = (0..nl).map(|v| lattice.position(v)).collect();
    // Labels: +1 inside, −1 outside, 0 on the surface.
    let mut label: Vec<i8> = position
        .iter()
        .map(|&p| {
            let d = sdf.distance(p);
            if d < 0.0 {
                1
            } else if d > 0.0 {
                -1
            } else {
                0
            }
        })
        .collect();
    // The lattice edges, long or short.
    let mut edges: Vec<(u32, u32, bool)> = Vec::new();
    for k in 0..=n[2] {
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                let b = lattice.black(i, j, k) as u32;
                if i < n[0] {
                    edges.push((b, lattice.black(i + 1, j, k) as u32, true));
                }
                if j < n[1] {
                    edges.push((b, lattice.black(i, j + 1, k) as u32, true));
                }
                if k < n[2] {
                    edges.push((b, lattice.black(i, j, k + 1) as u32, true));
                }
            }
        }
    }
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let r = lattice.red(i, j, k) as u32;
                if i + 1 < n[0] {
                    edges.push((r, lattice.red(i + 1, j, k) as u32, true));
                }
                if j + 1 < n[1] {
                    edges.push((r, lattice.red(i, j + 1, k) as u32, true));
                }
                if k + 1 < n[2] {
                    edges.push((r, lattice.red(i, j, k + 1) as u32, true));
                }
                for c in 0..8 {
                    let b = lattice.black(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1)) as u32;
                    edges.push((r, b, false));
                }
            }
        }
    }
    // Warping: each violated lattice point moves to its closest violating cut point.
    let mut warp: Vec<Option<(f64, Point)>> = vec![None; nl];
    for &(a, b, long) in &edges {
        let (la, lb) = (label[a as usize], label[b as usize]);
        if la * lb >= 0 {
            continue;
        }
        let (pa, pb) = (position[a as usize], position[b as usize]);
        let c = cut_point(sdf, pa, pb);
        let len = dist(pa, pb);
        let alpha = if long { ALPHA_LONG } else { ALPHA_SHORT };
        for (v, p) in [(a, pa), (b, pb)] {
            let d = dist(p, c);
            if d < alpha * len && warp[v as usize].is_none_or(|(best, _)| d < best) {
                warp[v as usize] = Some((d, c));
            }
        }
    }
    for (v, w) in warp.iter().enumerate() {
        if let Some((_, c)) = w {
            position[v] = *c;
            label[v] = 0;
        }
    }
    // Cut points of the warped lattice.
    let mut cuts: HashMap<(u32, u32), u32> = HashMap::new();
    let mut cut_positions: Vec<Point> = Vec::new();
    for &(a, b, _) in &edges {
        if label[a as usize] * label[b as usize] < 0 {
            let key = (a.min(b), a.max(b));
            cuts.insert(key, (nl + cut_positions.len()) as u32);
            cut_positions.push(cut_point(sdf, position[a as usize], position[b as usize]));
        }
    }
    let cut = |a: u32, b: u32| cuts[&(a.min(b), a.max(b))];
    // Filling.
    let mut tets: Vec<[u32; 4]> = Vec::new();
    let mut emit_lattice_tet = |t: [u32; 4]| {
        let pos: Vec<u32> = t.iter().copied().filter(|&v| label[v as usize] > 0).collect();
        if pos.is_empty() {
            return;
        }
        let zero: Vec<u32> = t.iter().copied().filter(|&v| label[v as usize] == 0).collect();
        let neg: Vec<u32> = t.iter().copied().filter(|&v| label[v as usize] < 0).collect();
        match (pos.len(), neg.len()) {
            (_, 0) => tets.push(t),
            (1, _) => {
                let mut v = vec![pos[0]];
                v.extend(&zero);
                v.extend(neg.iter().map(|&q| cut(pos[0], q)));
                tets.push([v[0], v[1], v[2], v[3]]);
            }
            (2, 1) => {
                let (p1, p2, z, q) = (pos[0], pos[1], zero[0], neg[0]);
                for tri in split_quad([p1, p2, cut(p2, q), cut(p1, q)]) {
                    tets.push([z, tri[0], tri[1], tri[2]]);
                }
            }
            (2, 2) => {
                let (p1, p2, n1, n2) = (pos[0], pos[1], neg[0], neg[1]);
                tets.extend(split_prism([p1, cut(p1, n1), cut(p1, n2)], [p2, cut(p2, n1), cut(p2, n2)]));
            }
            (3, 1) => {
                let q = neg[0];
                tets.extend(split_prism(
                    [pos[0], pos[1], pos[2]],
                    [cut(pos[0], q), cut(pos[1], q), cut(pos[2], q)],
                ));
            }
            _ => unreachable!("four vertices"),
        }
    };
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let r1 = lattice.red(i, j, k) as u32;
                // The three red neighbours in +x, +y, +z and the shared face's corners.
                let b = |di: usize, dj: usize, dk: usize| lattice.black(i + di, j + dj, k + dk) as u32;
                if i + 1 < n[0] {
                    let r2 = lattice.red(i + 1, j, k) as u32;
                    let f = [b(1, 0, 0), b(1, 1, 0), b(1, 1, 1), b(1, 0, 1)];
                    for m in 0..4 {
                        emit_lattice_tet([r1, r2, f[m], f[(m + 1) % 4]]);
                    }
                }
                if j + 1 < n[1] {
                    let r2 = lattice.red(i, j + 1, k) as u32;
                    let f = [b(0, 1, 0), b(1, 1, 0), b(1, 1, 1), b(0, 1, 1)];
                    for m in 0..4 {
                        emit_lattice_tet([r1, r2, f[m], f[(m + 1) % 4]]);
                    }
                }
                if k + 1 < n[2] {
                    let r2 = lattice.red(i, j, k + 1) as u32;
                    let f = [b(0, 0, 1), b(1, 0, 1), b(1, 1, 1), b(0, 1, 1)];
                    for m in 0..4 {
                        emit_lattice_tet([r1, r2, f[m], f[(m + 1) % 4]]);
                    }
                }
            }
        }
    }
    // Compact the used vertices; drop flat tetrahedra.
    let all_position =
        |v: u32| if (v as usize) < nl { position[v as usize] } else { cut_positions[v as usize - nl] };
    let mut index: HashMap<u32, u32> = HashMap::new();
    let mut g = Vec::new();
    let mut surface = Vec::new();
    let mut cells = Vec::with_capacity(4 * tets.len());
    let mut dropped_flat = 0;
    let flat = 1e-9 * h * h * h;
    for t in &tets {
        let p: Vec<Point> = t.iter().map(|&v| all_position(v)).collect();
        if signed_volume(3, &p).abs() <= flat {
            dropped_flat += 1;
            continue;
        }
        for &v in t {
            let next = index.len() as u32;
            let id = *index.entry(v).or_insert_with(|| {
                let q = all_position(v);
                g.extend_from_slice(&q);
                if v as usize >= nl || label[v as usize] == 0 {
                    surface.push(next);
                }
                next
            });
            cells.push(id);
        }
    }
    if cells.is_empty() {
        return Err(MeshError::Generation(format!("isosurface stuffing: no inside at spacing {h}")));
    }
    let mesh = SimplexMesh::new(3, g, cells)?;
    Ok(Stuffed { mesh, surface, dropped_flat })
}

/// Splits quad `q` (in cyclic order) by the diagonal through its smallest index.
fn split_quad(q: [u32; 4]) -> [[u32; 3]; 2] {
    let m = (0..4).min_by_key(|&i| q[i]).expect("four corners");
    let (a, b, c, d) = (q[m], q[(m + 1) % 4], q[(m + 2) % 4], q[(m + 3) % 4]);
    [[a, b, c], [a, c, d]]
}

/// Splits the triangular prism with ends `a` and `b` (a_i–b_i the lateral edges) into three
/// tetrahedra with every quadrilateral split through its smallest index (Dompierre et al.).
fn split_prism(a: [u32; 3], b: [u32; 3]) -> [[u32; 4]; 3] {
    // Put the smallest of the six vertices at a[0].
    let (mut a, mut b) = (a, b);
    if b.iter().min() < a.iter().min() {
        std::mem::swap(&mut a, &mut b);
    }
    let r = (0..3).min_by_key(|&i| a[i]).expect("three");
    let a = [a[r], a[(r + 1) % 3], a[(r + 2) % 3]];
    let b = [b[r], b[(r + 1) % 3], b[(r + 2) % 3]];
    // Both quads at a0 are split through a0: the tetrahedron (a0, b0, b1, b2), then the
    // pyramid a0 over the quad (a1, a2, b2, b1).
    let first = [a[0], b[0], b[1], b[2]];
    let quad = [a[1], a[2], b[2], b[1]];
    let m = (0..4).min_by_key(|&i| quad[i]).expect("four");
    let [t1, t2] = if m == 0 || m == 2 {
        // Diagonal a1–b2.
        [[a[0], a[1], a[2], b[2]], [a[0], a[1], b[2], b[1]]]
    } else {
        // Diagonal a2–b1.
        [[a[0], a[1], a[2], b[1]], [a[0], a[2], b[2], b[1]]]
    };
    [first, t1, t2]
}

/// The six dihedral angles of a tetrahedron, in degrees.
pub fn dihedral_angles(p: &[Point]) -> [f64; 6] {
    let n: Vec<Point> = (0..4).map(|k| face_area_normal(3, p, k)).collect();
    let mut out = [0.0; 6];
    let mut e = 0;
    for k in 0..4 {
        for l in k + 1..4 {
            let (a, b) = (n[k], n[l]);
            let cos = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
                / ((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) * (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]))
                    .sqrt();
            out[e] = 180.0 - cos.clamp(-1.0, 1.0).acos().to_degrees();
            e += 1;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::sdf::{Capsule, Sphere, Union};
    use crate::mesh::Topology;

    fn angle_range(m: &SimplexMesh) -> (f64, f64) {
        let mut lo = 180.0f64;
        let mut hi = 0.0f64;
        for c in 0..m.cell_count() {
            for a in dihedral_angles(&m.cell_points(c)) {
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        (lo, hi)
    }

    #[test]
    fn a_stuffed_ball_is_a_closed_manifold_of_the_right_volume() {
        let ball = Sphere { centre: [0.1, -0.2, 0.05], radius: 1.0 };
        let s = stuff(&ball, 0.15, &CellBudget::machine()).expect("stuffed");
        let vol: f64 = s.mesh.volumes().iter().sum();
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        // The surface is interpolated by triangles of size ~h: volume within 2 %.
        assert!((vol - exact).abs() < 0.02 * exact, "volume {vol} vs {exact}");
        let topo = Topology::new(&s.mesh, None).expect("manifold");
        // Every boundary vertex lies on the sphere.
        for &f in topo.boundary_faces() {
            let [c, _] = topo.face_cells(f as usize);
            let l = topo.face_local(f as usize)[0] as usize;
            for (i, &v) in s.mesh.cell(c as usize).iter().enumerate() {
                if i != l {
                    let r = dist(s.mesh.point(v as usize), ball.centre);
                    assert!((r - 1.0).abs() < 1e-9, "boundary vertex {v} at radius {r}");
                }
            }
        }
        let (lo, hi) = angle_range(&s.mesh);
        eprintln!(
            "ball: {} tetrahedra, dihedral angles {lo:.2}° … {hi:.2}°, {} flat dropped",
            s.mesh.cell_count(),
            s.dropped_flat
        );
    }

    #[test]
    fn stuffed_meshes_keep_their_dihedral_angles_in_bounds() {
        let shape = Union(vec![
            Box::new(Sphere { centre: [0.0, 0.0, 0.0], radius: 1.0 }),
            Box::new(Sphere { centre: [2.2, 0.3, 0.0], radius: 0.5 }),
            Box::new(Capsule { a: [0.5, 0.0, 0.0], b: [2.0, 0.3, 0.0], radius: 0.18 }),
        ]);
        for h in [0.1, 0.137] {
            let s = stuff(&shape, h, &CellBudget::machine()).expect("stuffed");
            let (lo, hi) = angle_range(&s.mesh);
            eprintln!(
                "union at h = {h}: {} tetrahedra, dihedral angles {lo:.2}° … {hi:.2}°",
                s.mesh.cell_count()
            );
            Topology::new(&s.mesh, None).expect("manifold");
            assert!(
                lo >= 10.7 && hi <= 164.8,
                "dihedral angles {lo}° … {hi}° outside Labelle & Shewchuk's bounds"
            );
        }
        // Balls at many offsets against the lattice: every way the surface crosses it.
        for i in 0..12 {
            let t = i as f64 / 12.0;
            let ball = Sphere { centre: [0.37 * t, 0.61 * t * t, -0.23 * t], radius: 0.7 + 0.05 * t };
            let s = stuff(&ball, 0.1, &CellBudget::machine()).expect("stuffed");
            let (lo, hi) = angle_range(&s.mesh);
            assert!(lo >= 10.7 && hi <= 164.8, "offset {i}: dihedral angles {lo}° … {hi}°");
            assert_eq!(s.dropped_flat, 0);
        }
    }

    /// The estimate a budget is checked against bounds the cells built from above, for a ball
    /// filling its box and for a union that fills a small share of it (thin capsule
    /// included), without over-counting the latter by the empty box; a budget below it refuses
    /// the mesh before it is built.
    #[test]
    fn the_cell_estimate_bounds_the_mesh_from_above() {
        let union = Union(vec![
            Box::new(Sphere { centre: [0.0, 0.0, 0.0], radius: 1.0 }),
            Box::new(Sphere { centre: [2.2, 0.3, 0.0], radius: 0.5 }),
            Box::new(Capsule { a: [0.5, 0.0, 0.0], b: [2.0, 0.3, 0.0], radius: 0.05 }),
        ]);
        let ball = Sphere { centre: [0.1, -0.2, 0.05], radius: 1.0 };
        for (what, sdf, h) in [("ball", &ball as &dyn Sdf, 0.15), ("union", &union, 0.1)] {
            let built = stuff(sdf, h, &CellBudget::machine()).expect("stuffed").mesh.cell_count() as f64;
            let estimate = cell_estimate(sdf, h);
            let (lo, hi) = sdf.bounds();
            let whole_box: f64 = (0..3).map(|k| ((hi[k] - lo[k]) / h).ceil() + 4.0).product();
            eprintln!("{what}: {built} cells, estimate {estimate:.0}, whole box {:.0}", 10.0 * whole_box);
            assert!(estimate >= built, "{what}: estimate {estimate} below the {built} cells built");
            assert!(estimate < 4.0 * built, "{what}: estimate {estimate} for {built} cells");
            let e = stuff(sdf, h, &CellBudget::cells(0.5 * built)).unwrap_err().to_string();
            assert!(e.contains(&format!("spacing {h}")) && e.contains("raise the spacing"), "{e}");
        }
    }
}
