//! Synthetic spectral-element data sets for tests, demos and benchmarks. The fields are
//! analytic functions sampled at the element's nodes (interpolation; for Bernstein bases the
//! interpolant's Bernstein coefficients), not solutions of a solver.
//!
//! - [`quad_grid`]: a rectangle of straight-sided quadrilaterals whose interior vertices are
//!   displaced, so the elements are general bilinear (not parallelograms).
//! - [`annulus`]: a sector of an annulus in polar elements, the circles represented by the
//!   geometry polynomial of the asked order — curved elements.
//!
//! - [`artery`] and [`coil`]: the seed's surface data sets (704 and 3332 curved elements),
//!   tubes in 3D with a field `pressure` over several time steps.
//! - [`hex_shell`]: curved hexahedra (a quarter cylindrical shell) with a field `temperature`,
//!   for cut planes.
//!
//! The planar meshes carry two fields: `waves` (smooth, several time steps) and `cells` (the same plus a
//! different constant per element: discontinuous across every edge, for the crack tests).

use super::basis::{Basis1d, NodeSet};
use super::error::SpectralError;
use super::mesh::{Field, Shape, SpectralMesh};

/// The smooth analytic field `waves` at time t.
pub fn waves(x: f64, y: f64, t: f64) -> f64 {
    (3.0 * x + 1.3 * t).sin() * (2.5 * y - 0.7 * t).cos() + 0.4 * x * y
}

/// The per-element offset of the discontinuous field `cells`.
pub fn cell_offset(e: usize) -> f64 {
    0.25 * (((e * 7919) % 13) as f64 / 12.0 - 0.5)
}

/// Time steps of the generated fields.
pub const STEPS: usize = 4;

/// Deterministic displacement in [−1, 1] of vertex `k` (SplitMix64; no RNG dependency).
fn jitter(k: u64) -> f64 {
    let mut z = k.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(0x6A09_E667_F3BC_C909);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// An `nx` × `ny` grid of straight-sided quadrilaterals over [0, 2] × [0, 1], interior vertices
/// displaced by up to `skew` × the cell size, with fields of `order` on `set`.
pub fn quad_grid(
    nx: usize,
    ny: usize,
    skew: f64,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let (hx, hy) = (2.0 / nx as f64, 1.0 / ny as f64);
    let vertex = |i: usize, j: usize| -> [f64; 2] {
        let mut p = [i as f64 * hx, j as f64 * hy];
        if i > 0 && i < nx && j > 0 && j < ny {
            let k = (j * (nx + 1) + i) as u64;
            p[0] += skew * hx * jitter(2 * k);
            p[1] += skew * hy * jitter(2 * k + 1);
        }
        p
    };
    let geometry = Basis1d::new(NodeSet::Equispaced, 1)?;
    let mut points = Vec::with_capacity(nx * ny * 4);
    for j in 0..ny {
        for i in 0..nx {
            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = vertex(i + a, j + b);
                points.push([p[0], p[1], 0.0]);
            }
        }
    }
    with_fields(geometry, points, order, set)
}

/// A sector of the annulus 0.5 ≤ r ≤ 1, 0 ≤ θ ≤ 3π/2 in `nr` × `nt` polar elements whose
/// geometry is of `geometry_order` on GLL points, with fields of `order` on `set`.
pub fn annulus(
    nr: usize,
    nt: usize,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let geometry = Basis1d::new(NodeSet::GaussLobatto, geometry_order)?;
    let sweep = 1.5 * std::f64::consts::PI;
    let mut points = Vec::with_capacity(nr * nt * geometry.len() * geometry.len());
    for it in 0..nt {
        for ir in 0..nr {
            for &b in &geometry.nodes {
                for &a in &geometry.nodes {
                    let r = 0.5 + 0.5 * (ir as f64 + a) / nr as f64;
                    let th = sweep * (it as f64 + b) / nt as f64;
                    points.push([r * th.cos(), r * th.sin(), 0.0]);
                }
            }
        }
    }
    with_fields(geometry, points, order, set)
}

/// The seed's artery-like data set: a bent tube of varying radius (a stenosis) in
/// `along` × `around` curved elements (16 × 44 = 704 as in the seed) with geometry of
/// `geometry_order` on GLL points and fields of `order` on `set`.
pub fn artery(
    along: usize,
    around: usize,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let centre = |s: f64| {
        let th = 0.8 * std::f64::consts::PI * s;
        [1.5 * th.sin(), 1.5 * (1.0 - th.cos()), 0.15 * (2.0 * std::f64::consts::PI * s).sin()]
    };
    let radius = |s: f64| 0.25 * (1.0 - 0.35 * (-((s - 0.55) / 0.08).powi(2)).exp());
    tube(along, around, geometry_order, order, set, centre, radius)
}

/// The seed's coil-like data set: a helical tube of 7 turns in `along` × `around` curved
/// elements (238 × 14 = 3332 as in the seed).
pub fn coil(
    along: usize,
    around: usize,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let turns = 7.0;
    let centre = |s: f64| {
        let a = 2.0 * std::f64::consts::PI * turns * s;
        [a.cos(), a.sin(), 2.0 * s]
    };
    tube(along, around, geometry_order, order, set, centre, |_| 0.12)
}

/// A tube around the curve `centre(s)`, s ∈ [0, 1], of radius `radius(s)`, as quadrilateral
/// surface elements; the frame is (T, N = ẑ × T, B = T × N), with T the curve's tangent.
fn tube(
    along: usize,
    around: usize,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
    centre: impl Fn(f64) -> [f64; 3],
    radius: impl Fn(f64) -> f64,
) -> Result<SpectralMesh, SpectralError> {
    let geometry = Basis1d::new(NodeSet::GaussLobatto, geometry_order)?;
    let mut points = Vec::with_capacity(along * around * geometry.len() * geometry.len());
    let norm = |v: [f64; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|c| c / l)
    };
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    for ia in 0..along {
        for ir in 0..around {
            for &b in &geometry.nodes {
                for &a in &geometry.nodes {
                    let s = (ia as f64 + a) / along as f64;
                    let phi = 2.0 * std::f64::consts::PI * (ir as f64 + b) / around as f64;
                    let (p, q) = (centre(s - 1e-6), centre(s + 1e-6));
                    let t = norm([q[0] - p[0], q[1] - p[1], q[2] - p[2]]);
                    let n = norm(cross([0.0, 0.0, 1.0], t));
                    let bn = cross(t, n);
                    let (c, r) = (centre(s), radius(s));
                    points.push(std::array::from_fn(|k| c[k] + r * (phi.cos() * n[k] + phi.sin() * bn[k])));
                }
            }
        }
    }
    with_field(Shape::Quadrilateral, geometry, points, Basis1d::new(set, order)?, "pressure", pressure)
}

/// The mesh of `points` with one field `name` = `f(x, t)` sampled at [`STEPS`] times.
fn with_field(
    shape: Shape,
    geometry: Basis1d,
    points: Vec<[f64; 3]>,
    basis: Basis1d,
    name: &str,
    f: fn([f64; 3], f64) -> f64,
) -> Result<SpectralMesh, SpectralError> {
    let shell = SpectralMesh::new(shape, geometry, basis, points, Vec::new())?;
    let times: Vec<f64> = (0..STEPS).map(|k| 0.5 * k as f64).collect();
    let steps = times.iter().map(|&t| sample(&shell, |_, x| f(x, t))).collect();
    let fields = vec![Field { name: name.into(), times, steps }];
    SpectralMesh::new(shell.shape, shell.geometry, shell.basis, shell.points, fields)
}

/// The analytic field `pressure` of the tubes at time t: travelling waves along the tube.
pub fn pressure(x: [f64; 3], t: f64) -> f64 {
    (4.0 * x[0] - 1.5 * t).sin() * (3.0 * x[1] + 0.5 * t).cos() + 0.5 * (5.0 * x[2]).sin()
}

/// Samples `waves` (at [`STEPS`] times) and `cells` onto the mesh of `points`.
fn with_fields(
    geometry: Basis1d,
    points: Vec<[f64; 3]>,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let basis = Basis1d::new(set, order)?;
    let shell = SpectralMesh::new(Shape::Quadrilateral, geometry, basis.clone(), points, Vec::new())?;
    let times: Vec<f64> = (0..STEPS).map(|k| 0.5 * k as f64).collect();
    let steps = times.iter().map(|&t| sample(&shell, |_, x| waves(x[0], x[1], t))).collect();
    let cells = sample(&shell, |e, x| waves(x[0], x[1], 0.0) + cell_offset(e));
    let fields = vec![
        Field { name: "waves".into(), times: times.clone(), steps },
        Field { name: "cells".into(), times: vec![0.0], steps: vec![cells] },
    ];
    SpectralMesh::new(shell.shape, shell.geometry, shell.basis, shell.points, fields)
}

/// The coefficients of `f(e, x)` on every element of `mesh` in its field basis: values at the
/// nodes (a triangle's equispaced lattice), or for Bernstein the coefficients of the
/// interpolant at the GLL points.
pub fn sample(mesh: &SpectralMesh, f: impl Fn(usize, [f64; 3]) -> f64) -> Vec<f64> {
    let b = &mesh.basis;
    let m = b.len();
    let dim = mesh.shape.dim() as usize;
    let at = if b.set == NodeSet::Bernstein {
        super::basis::gauss_lobatto_nodes(b.order)
    } else {
        b.nodes.clone()
    };
    let per = mesh.values_per_element();
    let mut out = Vec::with_capacity(mesh.elements() * per);
    if let Some(shape) = mesh.shape.simplex() {
        // Equispaced nodes in simplex::triangle_index's or tetra_index's order.
        let n = b.order;
        for e in 0..mesh.elements() {
            for node in super::simplex::lattice(shape, n) {
                let r = node.map(|c| c as f64 / n as f64);
                let x = if shape == super::simplex::SimplexShape::Triangle {
                    mesh.map(e, r[0], r[1]).0
                } else {
                    mesh.map_hex(e, [r[0], r[1], r[2]]).0
                };
                out.push(f(e, x));
            }
        }
        return out;
    }
    for e in 0..mesh.elements() {
        let mut v: Vec<f64> = Vec::with_capacity(per);
        for flat in 0..per {
            let (i, j, k) = (flat % m, (flat / m) % m, flat / (m * m));
            let x = match mesh.shape {
                Shape::Hexahedron | Shape::Tetrahedron => mesh.map_hex(e, [at[i], at[j], at[k]]).0,
                Shape::Quadrilateral | Shape::Triangle => mesh.map(e, at[i], at[j]).0,
            };
            v.push(f(e, x));
        }
        if b.set == NodeSet::Bernstein {
            v = b.tensor_interpolate(&at, &v, dim);
        }
        out.extend(v);
    }
    out
}

/// The generated data sets by name (the command line's `--generate` values), for [`by_name`].
pub const DATA_SETS: [&str; 5] = ["grid", "annulus", "artery", "coil", "shell"];

/// The generated data sets by name (`galerkin spectral render --generate`): `grid` (8 × 4 straight,
/// skewed quadrilaterals), `annulus` (4 × 12 curved), `artery` (704 curved surface elements),
/// `coil` (3332) and `shell` (3 × 6 × 4 curved hexahedra, shown by cut planes), with geometry of `geometry_order` (curved sets) and fields of `order` on
/// `set`.
pub fn by_name(
    name: &str,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    match name {
        "grid" => quad_grid(8, 4, 0.25, order, set),
        "annulus" => annulus(4, 12, geometry_order, order, set),
        "artery" => artery(44, 16, geometry_order, order, set),
        "coil" => coil(238, 14, geometry_order, order, set),
        "shell" => hex_shell(3, 6, 4, geometry_order, order, set),
        other => Err(SpectralError::Missing(format!(
            "unknown data set {other:?} (available: {})",
            DATA_SETS.join(", ")
        ))),
    }
}

/// A curved hexahedral block for cut planes: the quarter cylindrical shell 0.5 ≤ r ≤ 1,
/// 0 ≤ θ ≤ π/2, 0 ≤ z ≤ 1 in `nr` × `nt` × `nz` hexahedra with geometry of `geometry_order`
/// on GLL points and a field `temperature` of `order` on `set` at [`STEPS`] times.
pub fn hex_shell(
    nr: usize,
    nt: usize,
    nz: usize,
    geometry_order: usize,
    order: usize,
    set: NodeSet,
) -> Result<SpectralMesh, SpectralError> {
    let geometry = Basis1d::new(NodeSet::GaussLobatto, geometry_order)?;
    let quarter = 0.5 * std::f64::consts::PI;
    let mut points = Vec::with_capacity(nr * nt * nz * geometry.len().pow(3));
    for iz in 0..nz {
        for it in 0..nt {
            for ir in 0..nr {
                for &c in &geometry.nodes {
                    for &b in &geometry.nodes {
                        for &a in &geometry.nodes {
                            let r = 0.5 + 0.5 * (ir as f64 + a) / nr as f64;
                            let th = quarter * (it as f64 + b) / nt as f64;
                            let z = (iz as f64 + c) / nz as f64;
                            points.push([r * th.cos(), r * th.sin(), z]);
                        }
                    }
                }
            }
        }
    }
    with_field(Shape::Hexahedron, geometry, points, Basis1d::new(set, order)?, "temperature", temperature)
}

/// The analytic field `temperature` of [`hex_shell`] at time t.
pub fn temperature(x: [f64; 3], t: f64) -> f64 {
    (4.0 * x[0] + t).sin() * (3.0 * x[1]).cos() * (2.5 * x[2] - 0.5 * t).cos() + 0.3 * x[2]
}
