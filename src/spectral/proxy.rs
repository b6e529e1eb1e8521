//! What the spectral renderer draws, built once on the CPU in f64 from the element geometry:
//!
//! - **Proxies** (per-pixel mode): a fan of triangles per element, from its centre to samples
//!   of its boundary, moved outward far enough that the proxy contains the whole curved element.
//!   The bound: a boundary edge c(s) of degree g, written in Bernstein form with control points
//!   B_k, has |c″| ≤ g (g − 1) max_k |B_{k+2} − 2 B_{k+1} + B_k| (the hodograph's convex hull),
//!   so a chord over a parameter interval of length h is within h² |c″|max / 8 of the curve.
//!   Fragments of the proxy whose inverse map leaves the reference square are discarded, so the
//!   element's true edge is drawn, not the proxy's. Every proxy, straight-sided ones too, is
//!   also moved out by [`OWNERSHIP_MARGIN`] of the element's size: neighbours' proxies then
//!   overlap along shared edges, so a pixel centre near an edge reaches both elements' fragment
//!   stages and the one that contains it wins by depth (`element.frag`), instead of whichever
//!   the rasteriser's tie rule (at 1/256 of a pixel) handed it to.
//! - **Node grids** (per-vertex mode, the seed's baseline): the element's nodes joined into an
//!   n × n grid of quads (two triangles each; on a triangle its lattice's n² small triangles),
//!   the field evaluated at the vertices and interpolated across.
//! - **Edges**: each element's four (a triangle's three) edges sampled at 2g segments on the true curve, drawn as
//!   lines (edge overdraw behind the faces; or in front, dark, to show the mesh).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};

use super::basis::{Basis1d, NodeSet, MAX_ORDER};
use super::mesh::{Shape, SpectralMesh};

/// One vertex of the spectral draws: world position, reference coordinates, element.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DrawVertex {
    /// World position.
    pub position: [f32; 3],
    /// Reference coordinates (ξ, η) in the element.
    pub reference: [f32; 2],
    /// The element.
    pub element: u32,
}

/// The three vertex streams of a mesh (no proxies for surfaces: they are tessellated).
pub struct DrawGeometry {
    /// Triangle list: the per-pixel proxies.
    pub proxies: Vec<DrawVertex>,
    /// Triangle list: the per-vertex node grids.
    pub node_grids: Vec<DrawVertex>,
    /// Line list: the element edges.
    pub edges: Vec<DrawVertex>,
}

/// Builds the proxies, node grids and edges of every element of `mesh`.
pub fn build(mesh: &SpectralMesh) -> DrawGeometry {
    let mut out = DrawGeometry { proxies: Vec::new(), node_grids: Vec::new(), edges: Vec::new() };
    let g = mesh.geometry.order;
    let bernstein = Basis1d::new(NodeSet::Bernstein, g).expect("same order as the geometry");
    for e in 0..mesh.elements() {
        if mesh.is_planar() {
            proxy(mesh, &bernstein, e, &mut out.proxies);
        }
        node_grid(mesh, e, &mut out.node_grids);
        edges(mesh, e, &mut out.edges);
    }
    out
}

fn vertex(mesh: &SpectralMesh, e: usize, r: [f64; 2]) -> DrawVertex {
    let (x, _) = mesh.map(e, r[0], r[1]);
    DrawVertex { position: x.map(|c| c as f32), reference: r.map(|c| c as f32), element: e as u32 }
}

/// The reference point at parameter s ∈ [0, 1] along edge `k` of the boundary, walked
/// counter-clockwise: on the reference square η = 0, ξ = 1, η = 1 (reversed), ξ = 0
/// (reversed); on the triangle η = 0, ξ + η = 1, ξ = 0 (reversed).
fn boundary(shape: Shape, k: usize, s: f64) -> [f64; 2] {
    match (shape, k) {
        (_, 0) => [s, 0.0],
        (Shape::Triangle, 1) => [1.0 - s, s],
        (Shape::Triangle, _) => [0.0, 1.0 - s],
        (_, 1) => [1.0, s],
        (_, 2) => [1.0 - s, 1.0],
        _ => [0.0, 1.0 - s],
    }
}

/// Edges of a 2D element: 3 for triangles, 4 for quadrilaterals.
fn edge_count(shape: Shape) -> usize {
    if shape == Shape::Triangle {
        3
    } else {
        4
    }
}

/// The reference centre: (1/3, 1/3) on the triangle, (1/2, 1/2) on the square.
fn centre_of(shape: Shape) -> [f64; 2] {
    if shape == Shape::Triangle {
        [1.0 / 3.0; 2]
    } else {
        [0.5; 2]
    }
}

/// Upper bound of |c″(s)| on edge `k` of element `e` (Bernstein second differences).
fn edge_curvature_bound(mesh: &SpectralMesh, bernstein: &Basis1d, e: usize, k: usize) -> f64 {
    let g = mesh.geometry.order;
    if g < 2 {
        return 0.0;
    }
    let nodes = &mesh.geometry.nodes;
    let along: Vec<[f64; 3]> = nodes
        .iter()
        .map(|&s| {
            let r = boundary(mesh.shape, k, s);
            mesh.map(e, r[0], r[1]).0
        })
        .collect();
    let control: Vec<[f64; 3]> = {
        let per: Vec<Vec<f64>> = (0..3)
            .map(|c| bernstein.interpolate(nodes, &along.iter().map(|p| p[c]).collect::<Vec<_>>()))
            .collect();
        (0..=g).map(|i| [per[0][i], per[1][i], per[2][i]]).collect()
    };
    let second = (0..g - 1)
        .map(|i| {
            let d: [f64; 3] =
                std::array::from_fn(|c| control[i + 2][c] - 2.0 * control[i + 1][c] + control[i][c]);
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .fold(0.0, f64::max);
    (g * (g - 1)) as f64 * second
}

/// How far every proxy reaches past its element, as a fraction of the element's size (see the
/// module docs): far above the rasteriser's snapping for elements of a pixel or more, and a
/// few per cent more fragments to discard.
pub const OWNERSHIP_MARGIN: f64 = 0.01;

/// A rational element's proxy polygon: the convex hull of its control points, which contains
/// the element when every weight is positive, each corner with its control point's Greville
/// abscissae as the Newton guess. (The boundary-sample polygon's curvature bound holds for
/// polynomial edges only.)
fn rational_ring(mesh: &SpectralMesh, e: usize) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    let nodes = &mesh.geometry.nodes;
    let m = nodes.len();
    let mut corners: Vec<([f64; 2], [f64; 2])> = mesh
        .element_points(e)
        .iter()
        .enumerate()
        .map(|(k, p)| ([p[0], p[1]], [nodes[k % m], nodes[k / m]]))
        .collect();
    corners.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]).then(a.0[1].total_cmp(&b.0[1])));
    // Andrew's monotone chain, counter-clockwise.
    let cross =
        |o: [f64; 2], a: [f64; 2], b: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let mut hull: Vec<([f64; 2], [f64; 2])> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let sweep: Vec<_> = if pass == 0 { corners.clone() } else { corners.iter().rev().copied().collect() };
        for c in sweep {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2].0, hull[hull.len() - 1].0, c.0) <= 0.0
            {
                hull.pop();
            }
            hull.push(c);
        }
        hull.pop();
    }
    (hull.iter().map(|c| c.1).collect(), hull.iter().map(|c| c.0).collect())
}

fn proxy(mesh: &SpectralMesh, bernstein: &Basis1d, e: usize, out: &mut Vec<DrawVertex>) {
    let g = mesh.geometry.order;
    let per_edge = g.max(1);
    let h = 1.0 / per_edge as f64;
    let (ring, mut points, mut dilation) = if mesh.weights.is_some() {
        let (ring, points) = rational_ring(mesh, e);
        (ring, points, 0.0)
    } else {
        let shape = mesh.shape;
        let edge_list = 0..edge_count(shape);
        let dilation = edge_list
            .clone()
            .map(|k| h * h / 8.0 * edge_curvature_bound(mesh, bernstein, e, k))
            .fold(0.0, f64::max);
        let ring: Vec<[f64; 2]> =
            edge_list.flat_map(|k| (0..per_edge).map(move |i| boundary(shape, k, i as f64 * h))).collect();
        let points: Vec<[f64; 2]> = ring
            .iter()
            .map(|r| {
                let (x, _) = mesh.map(e, r[0], r[1]);
                [x[0], x[1]]
            })
            .collect();
        (ring, points, dilation)
    };
    let n = points.len();
    let (lo, hi) = points.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
    });
    dilation = dilation.max(OWNERSHIP_MARGIN * (hi[0] - lo[0]).hypot(hi[1] - lo[1]));
    if dilation > 0.0 {
        // Plus f32 rounding of the vertices (relative 2⁻²³ of the coordinates).
        let size = points.iter().flatten().fold(0.0f64, |a, c| a.max(c.abs()));
        dilation += 4.0 * f64::from(f32::EPSILON) * size;
        let area: f64 = (0..n)
            .map(|i| {
                let (a, b) = (points[i], points[(i + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        let orient = area.signum();
        let normal = |a: [f64; 2], b: [f64; 2]| {
            let d = [b[0] - a[0], b[1] - a[1]];
            let l = d[0].hypot(d[1]).max(f64::MIN_POSITIVE);
            [orient * d[1] / l, -orient * d[0] / l]
        };
        let moved: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let (prev, p, next) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
                let (n1, n2) = (normal(prev, p), normal(p, next));
                let m = [n1[0] + n2[0], n1[1] + n2[1]];
                let dot = m[0] * n1[0] + m[1] * n1[1];
                // The miter: o · n1 = o · n2 = δ; at most 4δ long at sharp corners.
                let a =
                    if dot > 0.25 { dilation / dot } else { 4.0 * dilation / m[0].hypot(m[1]).max(1e-12) };
                [p[0] + a * m[0], p[1] + a * m[1]]
            })
            .collect();
        points = moved;
    }
    let centre = vertex(mesh, e, centre_of(mesh.shape));
    for i in 0..n {
        let j = (i + 1) % n;
        out.push(centre);
        for (p, r) in [(points[i], ring[i]), (points[j], ring[j])] {
            out.push(DrawVertex {
                position: [p[0] as f32, p[1] as f32, 0.0],
                reference: r.map(|c| c as f32),
                element: e as u32,
            });
        }
    }
}

fn node_grid(mesh: &SpectralMesh, e: usize, out: &mut Vec<DrawVertex>) {
    if mesh.shape == Shape::Triangle {
        // The equispaced lattice's n² small triangles (n(n+1)/2 upright, n(n−1)/2 inverted).
        let n = mesh.basis.order;
        let v = |i: usize, j: usize| vertex(mesh, e, [i as f64 / n as f64, j as f64 / n as f64]);
        for j in 0..n {
            for i in 0..n - j {
                out.extend([v(i, j), v(i + 1, j), v(i, j + 1)]);
                if i + j + 1 < n {
                    out.extend([v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]);
                }
            }
        }
        return;
    }
    let nodes = &mesh.basis.nodes;
    let m = nodes.len();
    for j in 0..m - 1 {
        for i in 0..m - 1 {
            let v = |a: usize, b: usize| vertex(mesh, e, [nodes[a], nodes[b]]);
            let (v00, v10, v01, v11) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
            out.extend([v00, v10, v11, v00, v11, v01]);
        }
    }
}

fn edges(mesh: &SpectralMesh, e: usize, out: &mut Vec<DrawVertex>) {
    let g = mesh.geometry.order;
    let segments = if g == 1 { 1 } else { 2 * g };
    for k in 0..edge_count(mesh.shape) {
        for s in 0..segments {
            let a = boundary(mesh.shape, k, s as f64 / segments as f64);
            let b = boundary(mesh.shape, k, (s + 1) as f64 / segments as f64);
            out.push(vertex(mesh, e, a));
            out.push(vertex(mesh, e, b));
        }
    }
}

/// Per element, for the surface tessellation (`tessellate.comp`): a sphere containing the
/// element (centre and radius of its Bernstein control net, whose convex hull contains it) and
/// K = max(|x_ξξ|, |x_ηη|) + |x_ξη| bounded on the whole element by the control net's
/// differences: |x_ξξ| ≤ g(g − 1) max|B_{i+2,j} − 2B_{i+1,j} + B_{ij}|, likewise η, and
/// |x_ξη| ≤ g² max|B_{i+1,j+1} − B_{i+1,j} − B_{i,j+1} + B_{ij}|. The last float is the height
/// scale (0: the geometry itself).
///
/// A rational surface is bounded through its polynomial interpolant of degree 2g + 2 (at most
/// [`MAX_ORDER`]; an estimate of K, which sets the tessellation level, not a bound), with the
/// sphere widened to contain the control points, whose convex hull contains the element.
///
/// Triangles: the same from the simplex Bernstein net ([`triangle_patches_of`]).
pub fn surface_patches(mesh: &SpectralMesh) -> Vec<[f32; 8]> {
    if mesh.shape == Shape::Triangle {
        return triangle_patches_of(mesh, mesh.geometry.order, 0.0, |e, r| mesh.map(e, r[0], r[1]).0);
    }
    if mesh.weights.is_none() {
        return patches_of(mesh, mesh.geometry.order, 0.0, |e, xi, eta| mesh.map(e, xi, eta).0);
    }
    let patches = patches_of(mesh, (2 * mesh.geometry.order + 2).min(MAX_ORDER), 0.0, |e, xi, eta| {
        mesh.map(e, xi, eta).0
    });
    containing_control_points(mesh, patches, |e, k| mesh.element_points(e)[k])
}

/// `patches` with each sphere grown to contain its element's control points (`control(e, k)`
/// of node k): a rational element lies in their convex hull.
fn containing_control_points(
    mesh: &SpectralMesh,
    mut patches: Vec<[f32; 8]>,
    control: impl Fn(usize, usize) -> [f64; 3],
) -> Vec<[f32; 8]> {
    for (e, patch) in patches.iter_mut().enumerate() {
        let centre = [patch[0], patch[1], patch[2]].map(f64::from);
        let reach = (0..mesh.points_per_element()).fold(0.0f64, |r, k| {
            let p = control(e, k);
            r.max(
                ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) + (p[2] - centre[2]).powi(2)).sqrt(),
            )
        });
        patch[3] = patch[3].max((reach * (1.0 + 1e-6)) as f32);
    }
    patches
}

/// [`surface_patches`] of the height field of a planar mesh: the surface
/// (x(ξ, η), y(ξ, η), `scale` · f(ξ, η)) of `field` at `step`, a vector polynomial of degree
/// max(g, n) per axis.
pub fn height_patches(mesh: &SpectralMesh, field: usize, step: usize, scale: f64) -> Vec<[f32; 8]> {
    let order = mesh.geometry.order.max(mesh.basis.order);
    let surface = |e, xi, eta| {
        let (x, _) = mesh.map(e, xi, eta);
        [x[0], x[1], scale * mesh.value(field, step, e, xi, eta)]
    };
    if mesh.shape == Shape::Triangle {
        return triangle_patches_of(mesh, order, scale, |e, r: [f64; 2]| surface(e, r[0], r[1]));
    }
    if mesh.weights.is_none() {
        return patches_of(mesh, order, scale, surface);
    }
    // Rational: as surface_patches; the control net of (x, y, scale f) is (X, Y, scale F).
    let patches = patches_of(mesh, (2 * order + 2).min(MAX_ORDER), scale, surface);
    containing_control_points(mesh, patches, |e, k| {
        let p = mesh.element_points(e)[k];
        [p[0], p[1], scale * mesh.element_values(field, step, e)[k]]
    })
}

/// The bounds of the surface `surface(e, ξ, η)`, a polynomial of degree `order` per axis: its
/// Bernstein control net from its values at the order's GLL points.
fn patches_of(
    mesh: &SpectralMesh,
    order: usize,
    scale: f64,
    surface: impl Fn(usize, f64, f64) -> [f64; 3],
) -> Vec<[f32; 8]> {
    let g = order;
    let m = g + 1;
    let bernstein = Basis1d::new(NodeSet::Bernstein, g).expect("an order of a mesh basis");
    let nodes = super::basis::gauss_lobatto_nodes(g);
    (0..mesh.elements())
        .map(|e| {
            let samples: Vec<[f64; 3]> = (0..m * m).map(|k| surface(e, nodes[k % m], nodes[k / m])).collect();
            let per: Vec<Vec<f64>> = (0..3)
                .map(|c| {
                    let v: Vec<f64> = samples.iter().map(|p| p[c]).collect();
                    bernstein.tensor_interpolate(&nodes, &v, 2)
                })
                .collect();
            let b = |i: usize, j: usize| [per[0][j * m + i], per[1][j * m + i], per[2][j * m + i]];
            let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            let comb = |terms: &[(f64, [f64; 3])]| {
                norm(std::array::from_fn(|c| terms.iter().map(|(w, p)| w * p[c]).sum::<f64>()))
            };
            let (mut xx, mut yy, mut xy) = (0.0f64, 0.0f64, 0.0f64);
            for j in 0..m {
                for i in 0..m {
                    if i + 2 < m {
                        xx = xx.max(comb(&[(1.0, b(i + 2, j)), (-2.0, b(i + 1, j)), (1.0, b(i, j))]));
                    }
                    if j + 2 < m {
                        yy = yy.max(comb(&[(1.0, b(i, j + 2)), (-2.0, b(i, j + 1)), (1.0, b(i, j))]));
                    }
                    if i + 1 < m && j + 1 < m {
                        xy = xy.max(comb(&[
                            (1.0, b(i + 1, j + 1)),
                            (-1.0, b(i + 1, j)),
                            (-1.0, b(i, j + 1)),
                            (1.0, b(i, j)),
                        ]));
                    }
                }
            }
            let gg = g as f64;
            let k = (gg * (gg - 1.0) * xx.max(yy)) + gg * gg * xy;
            let net: Vec<[f64; 3]> = (0..m * m).map(|t| [per[0][t], per[1][t], per[2][t]]).collect();
            patch_record(&net, k, scale)
        })
        .collect()
}

/// A patch of `surface_patches`: the sphere around the control points `net` (centre their
/// mean, radius the farthest), the curvature bound `k`, the height `scale`; rounded up so the
/// f32 sphere and bound still hold.
fn patch_record(net: &[[f64; 3]], k: f64, scale: f64) -> [f32; 8] {
    let count = net.len() as f64;
    let centre: [f64; 3] = std::array::from_fn(|c| net.iter().map(|p| p[c]).sum::<f64>() / count);
    let radius = net
        .iter()
        .map(|p| {
            ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) + (p[2] - centre[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    [
        centre[0] as f32,
        centre[1] as f32,
        centre[2] as f32,
        (radius * (1.0 + 1e-6)) as f32,
        (k * (1.0 + 1e-6)) as f32,
        scale as f32,
        0.0,
        0.0,
    ]
}

/// [`patches_of`] for triangles: the surface `surface(e, r)`, a polynomial of total degree
/// `order`, sampled at the equispaced lattice and turned into its simplex Bernstein net
/// `b_{ijk}` (i on ξ, j on η, k on 1 − ξ − η; [`super::simplex::ToBernstein`]). Along ξ the
/// barycentric step is e₀ − e₂, so x_ξξ = g(g − 1) Σ (b_{+2e₀} − 2b_{+e₀+e₂} + b_{+2e₂}) B over
/// the degree-(g − 2) Bernstein polynomials, likewise x_ηη with e₁, and
/// x_ξη = g(g − 1) Σ (b_{+e₀+e₁} − b_{+e₀+e₂} − b_{+e₁+e₂} + b_{+2e₂}) B; each is bounded by its
/// differences' largest norm (the B sum to 1), so K ≤ g(g − 1)(max(Dξξ, Dηη) + Dξη). The
/// tessellation's small right triangles then err by at most h²K/4 as a quadrilateral's do.
fn triangle_patches_of(
    mesh: &SpectralMesh,
    order: usize,
    scale: f64,
    surface: impl Fn(usize, [f64; 2]) -> [f64; 3],
) -> Vec<[f32; 8]> {
    use super::simplex::{lattice, triangle_index, SimplexShape, ToBernstein};
    let g = order;
    let convert = ToBernstein::new(SimplexShape::Triangle, g).expect("equispaced nodes are unisolvent");
    let nodes = lattice(SimplexShape::Triangle, g);
    (0..mesh.elements())
        .map(|e| {
            let samples: Vec<[f64; 3]> =
                nodes.iter().map(|b| surface(e, [b[0] as f64 / g as f64, b[1] as f64 / g as f64])).collect();
            let net = convert.control_points(&samples);
            // b(i, j): the control point of multi-index (i, j, g − i − j).
            let b = |i: usize, j: usize| net[triangle_index(g, i, j)];
            let norm = |terms: &[(f64, [f64; 3])]| {
                let v: [f64; 3] = std::array::from_fn(|c| terms.iter().map(|(w, p)| w * p[c]).sum::<f64>());
                (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
            };
            let (mut xx, mut yy, mut xy) = (0.0f64, 0.0f64, 0.0f64);
            // Over the degree-(g − 2) multi-indices (i, j, k = g − 2 − i − j).
            for j in 0..g.saturating_sub(1) {
                for i in 0..g - 1 - j {
                    xx = xx.max(norm(&[(1.0, b(i + 2, j)), (-2.0, b(i + 1, j)), (1.0, b(i, j))]));
                    yy = yy.max(norm(&[(1.0, b(i, j + 2)), (-2.0, b(i, j + 1)), (1.0, b(i, j))]));
                    xy = xy.max(norm(&[
                        (1.0, b(i + 1, j + 1)),
                        (-1.0, b(i + 1, j)),
                        (-1.0, b(i, j + 1)),
                        (1.0, b(i, j)),
                    ]));
                }
            }
            let gg = g as f64;
            patch_record(&net, gg * (gg - 1.0) * (xx.max(yy) + xy), scale)
        })
        .collect()
}

/// The tessellation level `tessellate.comp` gives a surface element (its twin, in the same f32
/// arithmetic): L = ceil(sqrt(P K / (4 z budget))) clamped to [1, `cap`], 0 for an element
/// wholly behind the eye; `patch` from [`surface_patches`], `focal` the pixels per world unit
/// at view depth 1, P = focal · (1 + the element's own off-axis tangent bound), z the element's
/// nearest view depth (derivation in `tessellate.comp`).
pub fn tessellation_level(patch: &[f32; 8], view_proj: &Mat4, focal: f32, budget: f32, cap: f32) -> u32 {
    let r = patch[3];
    let c = *view_proj * Vec4::new(patch[0], patch[1], patch[2], 1.0);
    let depth = c.w - r;
    if depth + 2.0 * r <= 0.0 {
        return 0;
    }
    let z = depth.max(1e-3 * r);
    let row =
        |k: usize| glam::Vec3::new(view_proj.x_axis[k], view_proj.y_axis[k], view_proj.z_axis[k]).length();
    let (sx, sy) = (row(0), row(1));
    let tx = (c.x.abs() + sx * r) / (sx * z);
    let ty = (c.y.abs() + sy * r) / (sy * z);
    let pixels = focal * (1.0 + (tx * tx + ty * ty).sqrt());
    let l = (pixels / z * patch[4] / (4.0 * budget)).sqrt().ceil();
    l.clamp(1.0, cap) as u32
}

/// Per hexahedron, the Bernstein control points of its geometry ((g + 1)³, ξ fastest; per
/// tetrahedron its simplex Bernstein points, [`super::simplex::ToBernstein`]):
/// their convex hull contains the element, so a plane that does not separate them misses it
/// (`cut.comp`).
pub fn bernstein_hull(mesh: &SpectralMesh) -> Result<Vec<[f32; 4]>, super::SpectralError> {
    let g = mesh.geometry.order;
    if mesh.shape == Shape::Tetrahedron {
        // The simplex's Bernstein control points (as many as its Lagrange nodes).
        let convert = super::simplex::ToBernstein::new(super::simplex::SimplexShape::Tetrahedron, g)
            .ok_or_else(|| {
                super::SpectralError::Missing(format!("no Bernstein form of order {g} tetrahedra"))
            })?;
        let mut out = Vec::with_capacity(mesh.points.len());
        for e in 0..mesh.elements() {
            let control = convert.control_points(mesh.element_points(e));
            out.extend(control.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0]));
        }
        return Ok(out);
    }
    let bernstein = Basis1d::new(NodeSet::Bernstein, g).expect("same order as the geometry");
    let dim = mesh.shape.dim() as usize;
    if mesh.geometry.set == NodeSet::Bernstein {
        // Bézier cells (rational ones too): the points are the control points already.
        return Ok(mesh.points.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0]).collect());
    }
    let mut out = Vec::with_capacity(mesh.points.len());
    for e in 0..mesh.elements() {
        let pts = mesh.element_points(e);
        let per: Vec<Vec<f64>> = (0..3)
            .map(|c| {
                let v: Vec<f64> = pts.iter().map(|p| p[c]).collect();
                bernstein.tensor_interpolate(&mesh.geometry.nodes, &v, dim)
            })
            .collect();
        out.extend((0..pts.len()).map(|k| [per[0][k] as f32, per[1][k] as f32, per[2][k] as f32, 0.0]));
    }
    Ok(out)
}

/// Per element of a solid mesh (hexahedra, tetrahedra), an interval [lo, hi] that contains
/// `field` at `step` everywhere in the element: the least and greatest of its Bernstein
/// coefficients. The Bernstein polynomials are non-negative and sum to one, so the field is a
/// convex combination of them — of rational cells' too, whose value Σ w F B / Σ w B weighs the
/// control values F by w B / Σ w B > 0. The isosurface pass draws only the elements whose
/// interval holds an iso value (`iso.vert`): no other element can contain a root.
pub fn value_bounds(
    mesh: &SpectralMesh,
    field: usize,
    step: usize,
) -> Result<Vec<[f64; 2]>, super::SpectralError> {
    let n = mesh.basis.order;
    let span = |c: &[f64]| c.iter().fold([f64::MAX, f64::MIN], |[lo, hi], &v| [lo.min(v), hi.max(v)]);
    match mesh.shape {
        Shape::Tetrahedron => {
            let convert = super::simplex::ToBernstein::new(super::simplex::SimplexShape::Tetrahedron, n)
                .ok_or_else(|| {
                    super::SpectralError::Missing(format!("no Bernstein form of order {n} tetrahedra"))
                })?;
            Ok((0..mesh.elements())
                .map(|e| span(&convert.control_values(mesh.element_values(field, step, e))))
                .collect())
        }
        Shape::Hexahedron => {
            if mesh.basis.set == NodeSet::Bernstein {
                return Ok((0..mesh.elements()).map(|e| span(mesh.element_values(field, step, e))).collect());
            }
            let bernstein = Basis1d::new(NodeSet::Bernstein, n)?;
            Ok((0..mesh.elements())
                .map(|e| {
                    span(&bernstein.tensor_interpolate(
                        &mesh.basis.nodes,
                        mesh.element_values(field, step, e),
                        3,
                    ))
                })
                .collect())
        }
        Shape::Quadrilateral | Shape::Triangle => Err(super::SpectralError::Missing(format!(
            "value bounds are made for solid elements; this mesh is of {:?}s",
            mesh.shape
        ))),
    }
}
