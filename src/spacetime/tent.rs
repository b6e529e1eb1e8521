//! A tent-pitching spacetime mesher (the *Tent Pitcher* of seed 003 §3.2, after Üngör and
//! Sheffer, seed reference \[25\]): a front over a conforming 2D triangulation advances by lifting
//! one vertex at a time in time, as far as a causality bound allows, and every lift fills a
//! *tent* of tetrahedra. Local refinement near moving wave fronts, slab by slab, makes the
//! spacetime mesh non-conforming, as in the seed's data (§3.2, §4: "a (potentially
//! nonconforming) simplicial decomposition of spacetime").
//!
//! # One slab
//!
//! The front is a piecewise-linear graph `t = τ(x)` over a conforming triangulation, starting
//! flat at `T0`. The vertex `v` with the **lowest** front time is pitched (a priority queue;
//! ties go to the lower vertex index). Its new time is the largest value the causality bound
//! allows, capped at `T1`: for every triangle `(v, a, b)` around `v`,
//!
//! ```text
//! t_v_new ≤ min(t_a, t_b) + s · h_v / c
//! ```
//!
//! with `h_v` the altitude of `v` (its distance to the line through `a`, `b`), `c` the wave
//! speed on the triangle ([`TentProblem::wave_speed`]) and `s` the safety factor
//! ([`TentOptions::safety`]). The lift emits one tetrahedron per triangle around `v`, with
//! corners `(a, b, v_old, v_new)` in that order (positively oriented: `6·volume = 2·area ·
//! (t_new − t_old)`).
//!
//! **Why this tiles the slab, conformingly.** Over a triangle `(v, a, b)` the region between
//! the front before and after the lift is `{(x, t) : τ_old(x) ≤ t ≤ τ_old(x) + (t_new −
//! t_old) λ_v(x)}` (`λ_v` the barycentric coordinate of `v`), which is exactly the
//! tetrahedron `(a, b, v_old, v_new)`. The fronts form a sequence `T0 = τ_0 ≤ τ_1 ≤ … ≤ τ_N =
//! T1` (every lift only raises the front), so every point of the slab lies between exactly one
//! pair of consecutive fronts (up to boundaries) and there over exactly one triangle: the
//! tetrahedra tile the slab and the volumes add up to `area · (T1 − T0)`. Faces match: within
//! a tent, neighbouring tetrahedra share the vertical face `(a, v_old, v_new)`; between tents,
//! the bottom face `(a, b, v_old)` of a tetrahedron is the current front facet over its
//! triangle, which is the top face of the tetrahedron that last raised that facet (or lies in
//! `t = T0`). So one slab is a conforming tetrahedral mesh.
//!
//! **Why the output is already sorted by lowest time** (seed 003 §4.1's sort key, which lets a
//! data set be streamed to disk in order). The pitched vertex is the global minimum of the
//! front, so its neighbours satisfy `t_a, t_b ≥ t_v_old` and each emitted tetrahedron's
//! lowest time is `t_v_old`. The minimum of the front never decreases: a lift changes one
//! value, the minimum, and raises it. So the sequence of `t_v_old`, which is the sequence of
//! the front's minima, is non-decreasing, and so are the emitted elements' lowest times.
//!
//! **Why no tetrahedron is degenerate.** Since `t_a, t_b ≥ t_v_old`, the bound is at least
//! `t_v_old + L_v` with `L_v = min s h_v / c` over the triangles around `v` (all `h_v > 0` on
//! a valid triangulation). A lift that would stop less than `L_v / 2` below `T1` (leaving a
//! sliver for the last lift) goes to the midpoint `(t_v_old + T1)/2` instead, which is still
//! within the bound; so every lift is at least `min(L_v / 2, T1 − T0)`, relative to element
//! sizes of order `h / c`.
//!
//! **The bound and the exact cone constraint.** The invariant `t_i ≤ min(others) + s h_i / c`
//! holds for every vertex `i` of every triangle at all times (it held when `i` was last lifted,
//! and the others have only risen since). With `m` the triangle's lowest time, `τ − m = Σ (t_i
//! − m) λ_i` has at most two non-zero terms, each with gradient at most `s / c`, so every front
//! facet satisfies `|∇τ| ≤ 2s / c`. With the default `s = 1/2` the front is therefore
//! everywhere *space-like* in the exact sense of the cone constraint `|∇τ| ≤ 1/c` of tent
//! pitching, not only in the simplified altitude form above.
//!
//! # Slabs and non-conforming refinement
//!
//! The time span is split into slabs `[T_k, T_{k+1}]` ([`TentOptions::slab_times`]). For each
//! slab the base triangulation is refined by [`TentOptions::refine_levels`] rounds of
//! newest-vertex bisection ([`Triangulation::refine`]) of the triangles where
//! [`TentProblem::near_front`] says a wave front passes during the slab; within the slab the
//! refined triangulation is conforming, and tents are pitched through the slab on it from a
//! flat front at `T_k` to a flat front at `T_{k+1}`. Neighbouring slabs generally have
//! different triangulations on their shared plane `t = T_k`, so faces there are not matched:
//! **the whole mesh is non-conforming** at slab boundaries (conforming inside each slab). The
//! slices still tile the domain at every time, including `t = T_k` (the slicer's convention,
//! [`super::slice`], takes the face in the plane from the element below it). Slab after slab
//! the output stays sorted by lowest time. Vertices are shared by index within a slab; the
//! flat front at `T_k` is created again for slab `k`.
//!
//! # Output
//!
//! [`pitch_tents`] streams every tetrahedron (corners, vertex indices, material) to a callback
//! so that huge meshes need not be held; [`count_tents`] is the same run without output (a dry
//! run, used to hit a requested element count); [`tent_mesh`] collects a [`SpacetimeMesh`] and
//! fills every element with the L2 projection of an analytic field
//! ([`super::generate::project_element`], in parallel).

use std::cmp::{Ordering, Reverse};
use std::collections::{BinaryHeap, HashMap};

use rayon::prelude::*;

use super::cubic::Material;
use super::generate::project_element;
use super::mesh::{ElementField, SpacetimeMesh};

/// The default safety factor `s` of the causality bound: `1/2`, the largest value for which the
/// altitude bound implies the exact cone constraint `|∇τ| ≤ 1/c` on every front facet (see the
/// module docs).
pub const DEFAULT_SAFETY: f64 = 0.5;

/// What the mesher refuses.
#[derive(Debug, thiserror::Error)]
pub enum TentError {
    /// A triangulation that is not a valid, counter-clockwise, edge-manifold one.
    #[error("triangulation: {0}")]
    Triangulation(String),
    /// A wave speed that is not positive and finite.
    #[error("triangle {triangle}: wave speed {speed} must be positive and finite")]
    WaveSpeed {
        /// The triangle (of the slab's refined triangulation).
        triangle: usize,
        /// The speed given.
        speed: f64,
    },
    /// Slab times that are not finite and strictly increasing, or fewer than two.
    #[error("slab times must be at least two finite, strictly increasing values, got {0:?}")]
    SlabTimes(Vec<f64>),
    /// A safety factor outside (0, 1].
    #[error("the safety factor must lie in (0, 1], got {0}")]
    Safety(f64),
    /// A material index the caller's material list does not have.
    #[error("element {element}: material {material} does not exist ({count} materials)")]
    Material {
        /// The element.
        element: usize,
        /// The index returned by [`TentProblem::material`].
        material: u32,
        /// Number of materials given.
        count: usize,
    },
    /// More vertices than 32-bit indices can address.
    #[error("the mesh needs more than 2^32 vertices")]
    TooLarge,
}

/// A planar triangulation: points and counter-clockwise triangles. A triangle `[v0, v1, v2]`
/// has its *refinement edge* `v1–v2` opposite its *newest vertex* `v0` (newest-vertex
/// bisection, [`Triangulation::refine`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Triangulation {
    /// Points (x, y).
    pub points: Vec<[f64; 2]>,
    /// Triangles: three point indices each, counter-clockwise.
    pub triangles: Vec<[u32; 3]>,
}

/// The undirected key of an edge.
fn edge_key(a: u32, b: u32) -> (u32, u32) {
    if a < b {
        (a, b)
    } else {
        (b, a)
    }
}

/// Twice the signed area of the triangle `p`.
fn twice_signed_area(p: [[f64; 2]; 3]) -> f64 {
    (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])
}

impl Triangulation {
    /// The rectangle `[origin, origin + size]` as `nx × ny` squares, each split along its
    /// diagonal from lower left to upper right into two triangles (`2 nx ny` triangles; the
    /// diagonal is each triangle's refinement edge, so bisection keeps right isosceles shapes).
    pub fn rectangle(origin: [f64; 2], size: [f64; 2], nx: usize, ny: usize) -> Result<Self, TentError> {
        if !(size[0] > 0.0 && size[1] > 0.0 && size[0].is_finite() && size[1].is_finite()) {
            return Err(TentError::Triangulation(format!("rectangle size {size:?} must be positive")));
        }
        Self::mapped(nx, ny, |[u, v]| [origin[0] + size[0] * u, origin[1] + size[1] * v])
    }

    /// The unit-square grid of [`Triangulation::rectangle`] (`nx × ny` squares, `(u, v)` in
    /// `[0, 1]²`) with every point moved by `map`. The map must preserve orientation and keep
    /// the triangles non-degenerate; this is checked ([`Triangulation::check`]).
    pub fn mapped(nx: usize, ny: usize, map: impl Fn([f64; 2]) -> [f64; 2]) -> Result<Self, TentError> {
        if nx == 0 || ny == 0 {
            return Err(TentError::Triangulation(format!("grid {nx} × {ny} must have cells")));
        }
        let count = (nx + 1).checked_mul(ny + 1).filter(|&c| c <= u32::MAX as usize);
        if count.is_none() {
            return Err(TentError::TooLarge);
        }
        let mut points = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                points.push(map([i as f64 / nx as f64, j as f64 / ny as f64]));
            }
        }
        let mut triangles = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let p = |di: usize, dj: usize| ((j + dj) * (nx + 1) + i + di) as u32;
                // Counter-clockwise, the diagonal p00–p11 opposite the first corner.
                triangles.push([p(1, 0), p(1, 1), p(0, 0)]);
                triangles.push([p(0, 1), p(0, 0), p(1, 1)]);
            }
        }
        let t = Self { points, triangles };
        t.check()?;
        Ok(t)
    }

    /// An annular sector around the origin: radii `[inner, outer]`, polar angles
    /// `[−half_angle, half_angle]`, as the polar image of an `nr × na` grid (straight edges
    /// between the mapped points, so the curved boundaries are polygons).
    pub fn annular_sector(
        inner: f64,
        outer: f64,
        half_angle: f64,
        nr: usize,
        na: usize,
    ) -> Result<Self, TentError> {
        if !(inner > 0.0 && outer > inner && outer.is_finite()) {
            return Err(TentError::Triangulation(format!("radii {inner}, {outer} need 0 < inner < outer")));
        }
        if !(half_angle > 0.0 && half_angle < std::f64::consts::PI) {
            return Err(TentError::Triangulation(format!("half angle {half_angle} must lie in (0, π)")));
        }
        Self::mapped(nr, na, |[u, v]| {
            let r = inner + u * (outer - inner);
            let a = half_angle * (2.0 * v - 1.0);
            [r * a.cos(), r * a.sin()]
        })
    }

    /// The corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [[f64; 2]; 3] {
        self.triangles[t].map(|i| self.points[i as usize])
    }

    /// The area of triangle `t` (positive for a counter-clockwise triangle).
    pub fn triangle_area(&self, t: usize) -> f64 {
        0.5 * twice_signed_area(self.corners(t))
    }

    /// The total area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.triangle_area(t)).sum()
    }

    /// The altitude of corner `k` of triangle `t`: its distance to the line through the other
    /// two corners (the `h_v` of the causality bound).
    pub fn altitude(&self, t: usize, k: usize) -> f64 {
        let p = self.corners(t);
        let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
        twice_signed_area(p) / (b[0] - a[0]).hypot(b[1] - a[1])
    }

    /// The total length of the edges used by exactly one triangle. On a triangulation of a
    /// polygon without hanging vertices this is the polygon's perimeter; a hanging vertex on an
    /// edge makes that edge and its two halves all boundary edges, so the length grows.
    pub fn boundary_length(&self) -> f64 {
        let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
        for tri in &self.triangles {
            for k in 0..3 {
                *uses.entry(edge_key(tri[k], tri[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        uses.iter()
            .filter(|(_, &n)| n == 1)
            .map(|(&(a, b), _)| {
                let (p, q) = (self.points[a as usize], self.points[b as usize]);
                (q[0] - p[0]).hypot(q[1] - p[1])
            })
            .sum()
    }

    /// Checks what the mesher relies on: finite points, indices in range and distinct,
    /// counter-clockwise non-degenerate triangles (twice the area above `1e-14` of the longest
    /// edge squared), and every directed edge used at most once (so each edge has at most two
    /// triangles, on opposite sides). Hanging vertices are not detected here
    /// ([`Triangulation::boundary_length`] reveals them); [`Triangulation::rectangle`],
    /// [`Triangulation::mapped`] and [`Triangulation::refine`] never make any.
    pub fn check(&self) -> Result<(), TentError> {
        let bad = |s: String| Err(TentError::Triangulation(s));
        if self.points.len() > u32::MAX as usize {
            return Err(TentError::TooLarge);
        }
        for (i, p) in self.points.iter().enumerate() {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return bad(format!("point {i} {p:?} is not finite"));
            }
        }
        let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            if tri.iter().any(|&i| i as usize >= self.points.len()) {
                return bad(format!(
                    "triangle {t} {tri:?}: index out of range ({} points)",
                    self.points.len()
                ));
            }
            if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
                return bad(format!("triangle {t} {tri:?} repeats a point"));
            }
            let p = self.corners(t);
            let longest = (0..3)
                .map(|k| {
                    let (a, b) = (p[k], p[(k + 1) % 3]);
                    (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)
                })
                .fold(0.0, f64::max);
            if twice_signed_area(p) <= 1e-14 * longest {
                return bad(format!("triangle {t} {tri:?} is clockwise or degenerate"));
            }
            for k in 0..3 {
                if let Some(other) = directed.insert((tri[k], tri[(k + 1) % 3]), t) {
                    return bad(format!(
                        "triangles {other} and {t} share the directed edge {:?}",
                        (tri[k], tri[(k + 1) % 3])
                    ));
                }
            }
        }
        Ok(())
    }

    /// One round of newest-vertex bisection: every triangle with `marked[t]` (missing entries
    /// count as unmarked) is bisected along its refinement edge, and so is every triangle needed
    /// to keep the result conforming (closure: a triangle with a bisected edge also bisects its
    /// refinement edge). A triangle `[v0, v1, v2]` with midpoint `m` of `v1–v2` becomes
    /// `[m, v0, v1]` and `[m, v2, v0]` (newest vertex `m` first), which are bisected again along
    /// `v0–v1` or `v2–v0` if those edges are split: 2, 3 or 4 children. Midpoints of shared
    /// edges are shared, so the result is conforming within itself, covers the same polygon
    /// (midpoints of boundary edges stay on the straight edges) and keeps orientation.
    pub fn refine(&self, marked: &[bool]) -> Self {
        const PENDING: u32 = u32::MAX;
        let mut split: HashMap<(u32, u32), u32> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            if marked.get(t).copied().unwrap_or(false) {
                split.insert(edge_key(tri[1], tri[2]), PENDING);
            }
        }
        if split.is_empty() {
            return self.clone();
        }
        // Closure: terminates because edges are only ever added.
        loop {
            let mut changed = false;
            for tri in &self.triangles {
                let refinement = edge_key(tri[1], tri[2]);
                if !split.contains_key(&refinement)
                    && (split.contains_key(&edge_key(tri[0], tri[1]))
                        || split.contains_key(&edge_key(tri[2], tri[0])))
                {
                    split.insert(refinement, PENDING);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // Midpoints, numbered in triangle order (deterministic).
        let mut points = self.points.clone();
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if let Some(m) = split.get_mut(&edge_key(a, b)) {
                    if *m == PENDING {
                        *m = points.len() as u32;
                        let (p, q) = (self.points[a as usize], self.points[b as usize]);
                        points.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
                    }
                }
            }
        }
        fn bisect(tri: [u32; 3], split: &HashMap<(u32, u32), u32>, out: &mut Vec<[u32; 3]>) {
            match split.get(&edge_key(tri[1], tri[2])) {
                Some(&m) => {
                    bisect([m, tri[0], tri[1]], split, out);
                    bisect([m, tri[2], tri[0]], split, out);
                }
                None => out.push(tri),
            }
        }
        let mut triangles = Vec::with_capacity(self.triangles.len() + 3 * split.len());
        for &tri in &self.triangles {
            bisect(tri, &split, &mut triangles);
        }
        Self { points, triangles }
    }

    /// `levels` rounds of [`Triangulation::refine`], each marking the triangles with a corner or
    /// the centroid where `near` holds (stopping early when none is marked). `near` should
    /// include a margin of the triangle size so that a narrow feature between the sample
    /// points is not missed.
    pub fn refine_where(&self, levels: u32, near: impl Fn([f64; 2]) -> bool) -> Self {
        let mut t = self.clone();
        for _ in 0..levels {
            let marked: Vec<bool> = (0..t.triangles.len())
                .map(|i| {
                    let p = t.corners(i);
                    let centroid = [(p[0][0] + p[1][0] + p[2][0]) / 3.0, (p[0][1] + p[1][1] + p[2][1]) / 3.0];
                    p.iter().any(|&q| near(q)) || near(centroid)
                })
                .collect();
            if !marked.contains(&true) {
                break;
            }
            t = t.refine(&marked);
        }
        t
    }
}

/// What the mesher needs to know about the problem besides the base triangulation.
pub trait TentProblem: Sync {
    /// An upper bound of the wave speed on the triangle (corners counter-clockwise): the `c`
    /// of the causality bound. Must be positive and finite.
    fn wave_speed(&self, triangle: &[[f64; 2]; 3]) -> f64;

    /// Whether a wave front passes near `point` during `[slab_start, slab_end]`: the marker of
    /// local refinement. Should include a margin of the base triangle size (see
    /// [`Triangulation::refine_where`]). The default never refines.
    fn near_front(&self, slab_start: f64, slab_end: f64, point: [f64; 2]) -> bool {
        let _ = (slab_start, slab_end, point);
        false
    }

    /// The material index of an element, from its centroid `(x, y, t)`. The default is 0.
    fn material(&self, centroid: [f64; 3]) -> u32 {
        let _ = centroid;
        0
    }
}

/// A homogeneous medium: one wave speed, no refinement, material 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    /// The wave speed `c` (for elastodynamics the P-wave speed, [`Material::p_wave_speed`]).
    pub wave_speed: f64,
}

impl TentProblem for Homogeneous {
    fn wave_speed(&self, _triangle: &[[f64; 2]; 3]) -> f64 {
        self.wave_speed
    }
}

/// Slabs, refinement and the safety factor.
#[derive(Clone, Debug, PartialEq)]
pub struct TentOptions {
    /// Slab boundaries `T_0 < T_1 < … < T_m` (at least two values); the mesh covers
    /// `[T_0, T_m]`.
    pub slab_times: Vec<f64>,
    /// Rounds of newest-vertex bisection near the front in each slab (0: no refinement). Two
    /// rounds halve the edge lengths of right isosceles triangles.
    pub refine_levels: u32,
    /// The safety factor `s` in (0, 1] of the causality bound (default [`DEFAULT_SAFETY`]).
    pub safety: f64,
}

impl TentOptions {
    /// One slab `[t0, t1]`, no refinement, the default safety factor.
    pub fn new(t0: f64, t1: f64) -> Self {
        Self { slab_times: vec![t0, t1], refine_levels: 0, safety: DEFAULT_SAFETY }
    }

    /// `slabs` equal slabs over `[t0, t1]` (at least one), `refine_levels` rounds of refinement,
    /// the default safety factor.
    pub fn slabs(t0: f64, t1: f64, slabs: usize, refine_levels: u32) -> Self {
        let m = slabs.max(1);
        let mut slab_times: Vec<f64> = (0..m).map(|k| t0 + (t1 - t0) * k as f64 / m as f64).collect();
        slab_times.push(t1);
        Self { slab_times, refine_levels, safety: DEFAULT_SAFETY }
    }

    fn check(&self) -> Result<(), TentError> {
        let t = &self.slab_times;
        if t.len() < 2 || t.iter().any(|x| !x.is_finite()) || t.windows(2).any(|w| w[1] <= w[0]) {
            return Err(TentError::SlabTimes(t.clone()));
        }
        if !(self.safety > 0.0 && self.safety <= 1.0) {
            return Err(TentError::Safety(self.safety));
        }
        Ok(())
    }
}

/// One tetrahedron of the tent mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TentTet {
    /// Corners `(a, b, v_old, v_new)` (x, y, t): the base edge of the triangle `(v, a, b)`, the
    /// pitched vertex before and after its lift. Positively oriented.
    pub corners: [[f64; 3]; 4],
    /// Indices of the corners in the mesh's vertex list (shared within a slab, see
    /// [`tent_mesh`]).
    pub vertices: [u32; 4],
    /// The material ([`TentProblem::material`] of the centroid).
    pub material: u32,
    /// The slab it belongs to.
    pub slab: u32,
}

/// Counts of a tent-pitching run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TentStats {
    /// Tetrahedra.
    pub elements: usize,
    /// Vertices (the flat front of every slab plus one per lift).
    pub vertices: usize,
    /// Lifts (tents).
    pub pitches: usize,
    /// Triangles of each slab's (refined) triangulation.
    pub slab_triangles: Vec<usize>,
}

/// A time with a total order, for the priority queue.
#[derive(Clone, Copy, PartialEq)]
struct Time(f64);

impl Eq for Time {}

impl PartialOrd for Time {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Time {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// The triangulation of slab `slab`: the base refined near the front during the slab.
pub fn slab_triangulation<P: TentProblem + ?Sized>(
    base: &Triangulation,
    problem: &P,
    options: &TentOptions,
    slab: usize,
) -> Result<Triangulation, TentError> {
    options.check()?;
    let (t0, t1) = match (options.slab_times.get(slab), options.slab_times.get(slab + 1)) {
        (Some(&t0), Some(&t1)) => (t0, t1),
        _ => return Err(TentError::SlabTimes(options.slab_times.clone())),
    };
    Ok(base.refine_where(options.refine_levels, |p| problem.near_front(t0, t1, p)))
}

/// What a lift reports: the triangulation, the star of the vertex ((triangle, corner) pairs),
/// the front times before the lift, the vertex and its old and new time.
type OnPitch<'a> = dyn FnMut(&Triangulation, &[(u32, u8)], &[f64], u32, f64, f64) + 'a;

/// Pitches tents through one slab on a conforming triangulation, reporting every lift to
/// `on_pitch`.
fn pitch_slab<P: TentProblem + ?Sized>(
    tri: &Triangulation,
    problem: &P,
    safety: f64,
    (t0, t1): (f64, f64),
    on_pitch: &mut OnPitch<'_>,
) -> Result<(), TentError> {
    let n = tri.points.len();
    // s h / c per triangle corner.
    let mut lift = Vec::with_capacity(tri.triangles.len());
    for t in 0..tri.triangles.len() {
        let c = problem.wave_speed(&tri.corners(t));
        if !(c > 0.0 && c.is_finite()) {
            return Err(TentError::WaveSpeed { triangle: t, speed: c });
        }
        lift.push([0, 1, 2].map(|k| safety * tri.altitude(t, k) / c));
    }
    // Stars: (triangle, corner) pairs per vertex, compressed rows.
    let mut offsets = vec![0usize; n + 1];
    for tr in &tri.triangles {
        for &v in tr {
            offsets[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        offsets[v + 1] += offsets[v];
    }
    let mut fill = offsets.clone();
    let mut star = vec![(0u32, 0u8); offsets[n]];
    for (t, tr) in tri.triangles.iter().enumerate() {
        for (k, &v) in tr.iter().enumerate() {
            star[fill[v as usize]] = (t as u32, k as u8);
            fill[v as usize] += 1;
        }
    }
    let mut time = vec![t0; n];
    let mut queue: BinaryHeap<Reverse<(Time, u32)>> = (0..n as u32).map(|v| Reverse((Time(t0), v))).collect();
    while let Some(Reverse((Time(t_old), v))) = queue.pop() {
        let s = &star[offsets[v as usize]..offsets[v as usize + 1]];
        if s.is_empty() {
            time[v as usize] = t1;
            continue;
        }
        let (mut bound, mut least) = (f64::INFINITY, f64::INFINITY);
        for &(t, k) in s {
            let tr = tri.triangles[t as usize];
            let (a, b) = (tr[(k as usize + 1) % 3], tr[(k as usize + 2) % 3]);
            let l = lift[t as usize][k as usize];
            bound = bound.min(time[a as usize].min(time[b as usize]) + l);
            least = least.min(l);
        }
        let t_new = if bound >= t1 {
            t1
        } else if t1 - bound < 0.5 * least {
            // Do not leave a sliver below T1: go half way (still within the bound, see the
            // module docs).
            t_old + 0.5 * (t1 - t_old)
        } else {
            bound
        };
        on_pitch(tri, s, &time, v, t_old, t_new);
        time[v as usize] = t_new;
        if t_new < t1 {
            queue.push(Reverse((Time(t_new), v)));
        }
    }
    Ok(())
}

/// The run behind [`pitch_tents`], [`count_tents`] and [`tent_mesh`]: vertices are reported in
/// index order to `on_vertex`, tetrahedra to `on_tet` (none when counting).
fn run<P: TentProblem + ?Sized>(
    base: &Triangulation,
    problem: &P,
    options: &TentOptions,
    on_vertex: &mut dyn FnMut([f64; 3]),
    mut on_tet: Option<&mut dyn FnMut(&TentTet)>,
) -> Result<TentStats, TentError> {
    options.check()?;
    base.check()?;
    let mut stats = TentStats::default();
    for (slab, w) in options.slab_times.windows(2).enumerate() {
        let tri = slab_triangulation(base, problem, options, slab)?;
        stats.slab_triangles.push(tri.triangles.len());
        if stats.vertices + tri.points.len() > u32::MAX as usize {
            return Err(TentError::TooLarge);
        }
        // The flat front at T_k gets its own vertices.
        let mut id: Vec<u32> = (0..tri.points.len()).map(|p| (stats.vertices + p) as u32).collect();
        for p in &tri.points {
            on_vertex([p[0], p[1], w[0]]);
        }
        stats.vertices += tri.points.len();
        let mut overflow = false;
        pitch_slab(&tri, problem, options.safety, (w[0], w[1]), &mut |tri, s, time, v, t_old, t_new| {
            if overflow || stats.vertices >= u32::MAX as usize {
                overflow = true;
                return;
            }
            let new_id = stats.vertices as u32;
            let p = tri.points[v as usize];
            on_vertex([p[0], p[1], t_new]);
            stats.vertices += 1;
            stats.pitches += 1;
            stats.elements += s.len();
            if let Some(on_tet) = on_tet.as_mut() {
                for &(t, k) in s {
                    let tr = tri.triangles[t as usize];
                    let (a, b) = (tr[(k as usize + 1) % 3], tr[(k as usize + 2) % 3]);
                    let (pa, pb) = (tri.points[a as usize], tri.points[b as usize]);
                    let corners = [
                        [pa[0], pa[1], time[a as usize]],
                        [pb[0], pb[1], time[b as usize]],
                        [p[0], p[1], t_old],
                        [p[0], p[1], t_new],
                    ];
                    let centroid = std::array::from_fn(|j| {
                        0.25 * (corners[0][j] + corners[1][j] + corners[2][j] + corners[3][j])
                    });
                    let vertices = [id[a as usize], id[b as usize], id[v as usize], new_id];
                    let material = problem.material(centroid);
                    on_tet(&TentTet { corners, vertices, material, slab: slab as u32 });
                }
            }
            id[v as usize] = new_id;
        })?;
        if overflow {
            return Err(TentError::TooLarge);
        }
    }
    Ok(stats)
}

/// Meshes `[T_0, T_m] ×` the base triangulation with tents, slab by slab (module docs), and
/// hands every tetrahedron to `sink` in order of non-decreasing lowest time, without holding
/// the mesh. Materials come from [`TentProblem::material`] of each element's centroid.
pub fn pitch_tents<P: TentProblem + ?Sized>(
    base: &Triangulation,
    problem: &P,
    options: &TentOptions,
    sink: &mut dyn FnMut(&TentTet),
) -> Result<TentStats, TentError> {
    run(base, problem, options, &mut |_| {}, Some(sink))
}

/// The dry run of [`pitch_tents`]: the counts without any output (cheap: no corners, no
/// materials), used to choose a base resolution for a requested element count.
pub fn count_tents<P: TentProblem + ?Sized>(
    base: &Triangulation,
    problem: &P,
    options: &TentOptions,
) -> Result<TentStats, TentError> {
    run(base, problem, options, &mut |_| {}, None)
}

/// [`pitch_tents`] collected into a [`SpacetimeMesh`] (vertices shared by index within a
/// slab, elements sorted by lowest time) with `materials`, every element holding the L2
/// projection of `field` onto the cubic ([`project_element`], computed in parallel).
pub fn tent_mesh<P: TentProblem + ?Sized>(
    base: &Triangulation,
    problem: &P,
    options: &TentOptions,
    materials: Vec<Material>,
    field: &(impl Fn([f64; 3]) -> [f64; 2] + Sync),
) -> Result<SpacetimeMesh, TentError> {
    let mut vertices = Vec::new();
    let mut tets = Vec::new();
    let mut element_materials = Vec::new();
    let mut on_tet = |t: &TentTet| {
        tets.push(t.vertices);
        element_materials.push(t.material);
    };
    run(base, problem, options, &mut |p| vertices.push(p), Some(&mut on_tet))?;
    if let Some((e, &m)) = element_materials.iter().enumerate().find(|(_, &m)| m as usize >= materials.len())
    {
        return Err(TentError::Material { element: e, material: m, count: materials.len() });
    }
    let fields: Vec<ElementField> = (0..tets.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|e| {
            let (frame, coefficients) = project_element(tets[e].map(|i| vertices[i as usize]), field);
            ElementField { frame, material: element_materials[e], coefficients }
        })
        .collect();
    Ok(SpacetimeMesh { vertices, tets, fields, materials })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spacetime::mesh::six_volume;
    use crate::spacetime::slice::slice;

    /// Two media: c = 1 left of x = 0.5, c = 3 on triangles reaching beyond it.
    struct TwoSpeeds;

    impl TentProblem for TwoSpeeds {
        fn wave_speed(&self, t: &[[f64; 2]; 3]) -> f64 {
            if t.iter().any(|p| p[0] > 0.5) {
                3.0
            } else {
                1.0
            }
        }
    }

    /// A plane front `x = 0.1 + 0.8 t` in a medium with c = 1, refined within 0.1 of it.
    struct MovingFront;

    const BAND: f64 = 0.1;

    fn front(t: f64) -> f64 {
        0.1 + 0.8 * t
    }

    impl TentProblem for MovingFront {
        fn wave_speed(&self, _: &[[f64; 2]; 3]) -> f64 {
            1.0
        }

        fn near_front(&self, t0: f64, t1: f64, p: [f64; 2]) -> bool {
            p[0] >= front(t0) - BAND && p[0] <= front(t1) + BAND
        }

        fn material(&self, c: [f64; 3]) -> u32 {
            u32::from(c[0] > 0.5)
        }
    }

    const STEEL: Material = Material { lambda: 2.0, mu: 1.0, density: 1.0 };

    fn zero(_: [f64; 3]) -> [f64; 2] {
        [0.0; 2]
    }

    fn tets(base: &Triangulation, problem: &impl TentProblem, options: &TentOptions) -> Vec<TentTet> {
        let mut out = Vec::new();
        let stats = pitch_tents(base, problem, options, &mut |t| out.push(*t)).unwrap();
        assert_eq!(stats.elements, out.len());
        out
    }

    /// The causality bound on every tent (the tetrahedron's corners are the front at the lift:
    /// `a`, `b` and `v` before and after), a strictly positive lift, and the exact cone
    /// constraint `|∇τ| ≤ 2s/c` on the facet `(a, b, v_new)` the lift leaves on the front.
    fn check_tents(tets: &[TentTet], problem: &impl TentProblem, safety: f64) {
        for (e, t) in tets.iter().enumerate() {
            let [a, b, vo, vn] = t.corners;
            assert!(vn[2] > vo[2], "element {e}: lift {} → {}", vo[2], vn[2]);
            assert_eq!([vo[0], vo[1]], [vn[0], vn[1]]);
            let tri = [[vo[0], vo[1]], [a[0], a[1]], [b[0], b[1]]];
            let c = problem.wave_speed(&tri);
            let h = twice_signed_area(tri) / (b[0] - a[0]).hypot(b[1] - a[1]);
            let allowed = a[2].min(b[2]) + safety * h / c;
            assert!(vn[2] <= allowed + 1e-12 * (1.0 + allowed.abs()), "element {e}: {} > {allowed}", vn[2]);
            // Gradient of the linear time function over the facet (v, a, b) at the new time.
            let (d1, d2) = ([a[0] - vn[0], a[1] - vn[1]], [b[0] - vn[0], b[1] - vn[1]]);
            let (r1, r2) = (a[2] - vn[2], b[2] - vn[2]);
            let det = d1[0] * d2[1] - d1[1] * d2[0];
            let g = [(r1 * d2[1] - r2 * d1[1]) / det, (d1[0] * r2 - d2[0] * r1) / det];
            assert!(g[0].hypot(g[1]) <= 2.0 * safety / c * (1.0 + 1e-9), "element {e}: |∇τ| = {g:?}");
        }
    }

    fn slice_area(mesh: &SpacetimeMesh, t: f64) -> f64 {
        slice(mesh, t).iter().map(|p| p.area()).sum()
    }

    /// Sorted by lowest time, valid, volume = area × duration, and slices at `times` tile the
    /// domain. The relative tolerance 1e-9 is far above the rounding of summing a few thousand
    /// polygon areas and of the cut points (each exact to a few ulps of the coordinates), and
    /// far below any missing or doubled element (≥ 1e-4 of the area here).
    fn check_tiling(mesh: &SpacetimeMesh, area: f64, (t0, t1): (f64, f64), times: &[f64]) {
        mesh.validate().unwrap();
        let low = mesh.lowest_times();
        assert!(low.windows(2).all(|w| w[0] <= w[1]), "not sorted by lowest time");
        let volume: f64 = (0..mesh.tets.len()).map(|e| six_volume(mesh.corners(e)) / 6.0).sum();
        assert!((volume / (area * (t1 - t0)) - 1.0).abs() < 1e-9, "volume {volume} vs {}", area * (t1 - t0));
        for &t in times {
            let a = slice_area(mesh, t);
            assert!((a / area - 1.0).abs() < 1e-9, "slice at t = {t}: area {a} vs {area}");
        }
    }

    fn interior_times(mesh: &SpacetimeMesh, (t0, t1): (f64, f64)) -> Vec<f64> {
        // Vertex times (planes through vertices, edges and faces) and generic times.
        let mut times: Vec<f64> = mesh.vertices.iter().step_by(37).map(|p| p[2]).collect();
        times.extend([0.123, 0.5, 0.77].map(|s| t0 + s * (t1 - t0)));
        times.push(t1);
        times.retain(|&t| t > t0);
        times
    }

    #[test]
    fn grids_are_valid_counter_clockwise_triangulations() {
        let r = Triangulation::rectangle([1.0, -1.0], [2.0, 1.5], 4, 3).unwrap();
        assert_eq!((r.points.len(), r.triangles.len()), (20, 24));
        assert!((r.area() - 3.0).abs() < 1e-14);
        assert!((r.boundary_length() - 7.0).abs() < 1e-13);
        let s = Triangulation::annular_sector(0.5, 1.0, 0.4, 5, 8).unwrap();
        s.check().unwrap();
        // The polygon inscribed in the sector: 8 chords on each arc.
        let chord = |r: f64| 8.0 * 0.5 * r * r * (0.8f64 / 8.0).sin();
        assert!((s.area() - (chord(1.0) - chord(0.5))).abs() < 1e-13);
        // A reflecting map turns the triangles clockwise.
        assert!(Triangulation::mapped(2, 2, |[u, v]| [-u, v]).is_err());
        assert!(Triangulation::rectangle([0.0; 2], [1.0, 0.0], 2, 2).is_err());
        assert!(Triangulation::annular_sector(1.0, 0.5, 0.4, 2, 2).is_err());
    }

    #[test]
    fn bisection_keeps_the_triangulation_conforming() {
        for base in [
            Triangulation::rectangle([0.0; 2], [2.0, 1.0], 5, 3).unwrap(),
            Triangulation::annular_sector(0.4, 1.0, 0.5, 4, 5).unwrap(),
        ] {
            let (area, perimeter) = (base.area(), base.boundary_length());
            let mut t = base.clone();
            for round in 0..5 {
                let marked: Vec<bool> = (0..t.triangles.len()).map(|i| (i * 7 + round) % 5 == 0).collect();
                let before = t.triangles.len();
                t = t.refine(&marked);
                t.check().unwrap();
                assert!(t.triangles.len() >= before + marked.iter().filter(|&&m| m).count());
                assert!((t.area() / area - 1.0).abs() < 1e-13);
                // No hanging vertex: the boundary is still the polygon's perimeter.
                assert!((t.boundary_length() / perimeter - 1.0).abs() < 1e-13);
                // Euler characteristic of a disc: V − E + F = 1.
                let mut edges = std::collections::HashSet::new();
                for tri in &t.triangles {
                    for k in 0..3 {
                        edges.insert(edge_key(tri[k], tri[(k + 1) % 3]));
                    }
                }
                let euler = t.points.len() as i64 - edges.len() as i64 + t.triangles.len() as i64;
                assert_eq!(euler, 1);
            }
        }
        // Right isosceles triangles stay right isosceles: edge lengths are 2^(-k/2) multiples.
        let r = Triangulation::rectangle([0.0; 2], [1.0; 2], 1, 1).unwrap().refine(&[true, false]);
        assert_eq!(r.triangles.len(), 4);
    }

    #[test]
    fn tents_tile_one_slab_sorted_causal_and_non_degenerate() {
        let base = Triangulation::rectangle([0.0; 2], [1.0, 0.75], 7, 5).unwrap();
        for safety in [DEFAULT_SAFETY, 0.9] {
            let options = TentOptions { safety, ..TentOptions::new(0.25, 0.95) };
            let out = tets(&base, &TwoSpeeds, &options);
            check_tents(&out, &TwoSpeeds, safety);
            let mesh = tent_mesh(&base, &TwoSpeeds, &options, vec![STEEL], &zero).unwrap();
            assert_eq!(mesh.tets.len(), out.len());
            for (e, t) in out.iter().enumerate() {
                assert_eq!(mesh.corners(e), t.corners);
                assert_eq!(mesh.tets[e], t.vertices);
                assert!(six_volume(t.corners) > 0.0);
            }
            check_tiling(&mesh, base.area(), (0.25, 0.95), &interior_times(&mesh, (0.25, 0.95)));
            // Faster waves on the right: shorter tents there, so more elements per triangle.
            let right = out.iter().filter(|t| t.corners[2][0] > 0.6).count() as f64;
            let left = out.iter().filter(|t| t.corners[2][0] < 0.4).count() as f64;
            assert!(right > 1.5 * left, "{right} vs {left}");
        }
    }

    #[test]
    fn refined_slabs_are_non_conforming_and_finer_near_the_front() {
        let base = Triangulation::rectangle([0.0; 2], [1.0; 2], 8, 8).unwrap();
        let options = TentOptions::slabs(0.0, 1.0, 4, 2);
        let out = tets(&base, &MovingFront, &options);
        check_tents(&out, &MovingFront, options.safety);
        for k in 0..4 {
            let t = slab_triangulation(&base, &MovingFront, &options, k).unwrap();
            t.check().unwrap();
            assert!((t.boundary_length() - 4.0).abs() < 1e-12, "slab {k} has hanging vertices");
            assert!(t.triangles.len() > base.triangles.len());
        }
        let mesh = tent_mesh(&base, &MovingFront, &options, vec![STEEL, STEEL], &zero).unwrap();
        assert!(mesh.fields.iter().any(|f| f.material == 1) && mesh.fields.iter().any(|f| f.material == 0));
        let mut times = interior_times(&mesh, (0.0, 1.0));
        times.extend(&options.slab_times[1..]);
        check_tiling(&mesh, 1.0, (0.0, 1.0), &times);
        // At every inner slab boundary, the faces in the plane from below (slab k − 1's tops)
        // and from above (slab k's bottoms) both tile the square but are different sets.
        let key = |f: [[f64; 3]; 3]| {
            let mut k = f.map(|p| [p[0].to_bits(), p[1].to_bits()]);
            k.sort_unstable();
            k
        };
        for k in 1..4 {
            let tk = options.slab_times[k];
            let tops: Vec<_> = out
                .iter()
                .filter(|t| t.slab as usize == k - 1 && [0, 1, 3].iter().all(|&i| t.corners[i][2] == tk))
                .map(|t| [t.corners[0], t.corners[1], t.corners[3]])
                .collect();
            let bottoms: Vec<_> = out
                .iter()
                .filter(|t| t.slab as usize == k && [0, 1, 2].iter().all(|&i| t.corners[i][2] == tk))
                .map(|t| [t.corners[0], t.corners[1], t.corners[2]])
                .collect();
            let area = |fs: &[[[f64; 3]; 3]]| {
                fs.iter().map(|f| 0.5 * twice_signed_area(f.map(|p| [p[0], p[1]])).abs()).sum::<f64>()
            };
            assert!((area(&tops) - 1.0).abs() < 1e-12 && (area(&bottoms) - 1.0).abs() < 1e-12);
            let top_keys: std::collections::HashSet<_> = tops.iter().map(|&f| key(f)).collect();
            let unmatched = bottoms.iter().filter(|&&f| !top_keys.contains(&key(f))).count();
            assert!(unmatched > 0, "slab boundary {k} is conforming");
        }
        // Finer near the front: the spatial triangles under elements within the band are
        // smaller on average than those under elements far outside any slab's refined band
        // (which reaches 0.3 from the front: the band plus the front's travel in a slab).
        let (mut near, mut far) = ((0.0, 0usize), (0.0, 0usize));
        for t in &out {
            let c = t.corners;
            let (x, tc) =
                ((c[0][0] + c[1][0] + 2.0 * c[2][0]) / 4.0, (c[0][2] + c[1][2] + c[2][2] + c[3][2]) / 4.0);
            let a = 0.5 * twice_signed_area([c[2], c[0], c[1]].map(|p| [p[0], p[1]]));
            let d = (x - front(tc)).abs();
            if d < 0.5 * BAND {
                near.0 += a;
                near.1 += 1;
            } else if d > 0.45 {
                far.0 += a;
                far.1 += 1;
            }
        }
        let (mean_near, mean_far) = (near.0 / near.1 as f64, far.0 / far.1 as f64);
        assert!(mean_near < 0.3 * mean_far, "mean triangle area {mean_near} near, {mean_far} away");
    }

    #[test]
    fn bad_input_is_refused() {
        let base = Triangulation::rectangle([0.0; 2], [1.0; 2], 2, 2).unwrap();
        let h = Homogeneous { wave_speed: 1.0 };
        let count = |b: &Triangulation, p: &dyn Fn(&mut TentOptions), c: f64| {
            let mut o = TentOptions::new(0.0, 1.0);
            p(&mut o);
            count_tents(b, &Homogeneous { wave_speed: c }, &o)
        };
        assert!(matches!(
            count(&base, &|o| o.slab_times = vec![0.0, 0.5, 0.5], 1.0),
            Err(TentError::SlabTimes(_))
        ));
        assert!(matches!(count(&base, &|o| o.slab_times = vec![1.0], 1.0), Err(TentError::SlabTimes(_))));
        assert!(matches!(count(&base, &|o| o.slab_times[1] = f64::NAN, 1.0), Err(TentError::SlabTimes(_))));
        assert!(matches!(count(&base, &|o| o.safety = 0.0, 1.0), Err(TentError::Safety(_))));
        assert!(matches!(count(&base, &|o| o.safety = 1.5, 1.0), Err(TentError::Safety(_))));
        assert!(matches!(count(&base, &|_| {}, 0.0), Err(TentError::WaveSpeed { .. })));
        assert!(matches!(count(&base, &|_| {}, f64::INFINITY), Err(TentError::WaveSpeed { .. })));
        let mut flipped = base.clone();
        flipped.triangles[3].swap(0, 1);
        assert!(matches!(count(&flipped, &|_| {}, 1.0), Err(TentError::Triangulation(_))));
        let mut out_of_range = base.clone();
        out_of_range.triangles[0][2] = 99;
        assert!(matches!(count(&out_of_range, &|_| {}, 1.0), Err(TentError::Triangulation(_))));
        let no_materials = tent_mesh(&base, &h, &TentOptions::new(0.0, 1.0), vec![], &zero);
        assert!(matches!(no_materials, Err(TentError::Material { .. })));
        assert!(count(&base, &|_| {}, 1.0).is_ok());
    }
}
