//! Synthetic spacetime data sets. There is no spacetime DG solver here: the fields are
//! *analytic* elastodynamic solutions (plane pressure and shear pulses, which solve the
//! equations of linear elasticity exactly in a homogeneous medium) projected element by
//! element onto the 20 cubic monomials (an L2 projection per element, so the data are
//! discontinuous across faces exactly as a DG solution is). They are not solved.
//!
//! The mesh is a structured extrusion: a triangulated rectangle, extruded through time layers,
//! each prism split into three tetrahedra by the global vertex order (so neighbours agree on
//! the split and the mesh is conforming). The tent-pitching mesher, with local refinement near
//! wave fronts and non-conforming slabs, is [`super::tent`]; the seed's scenarios on it are
//! [`super::scenario`] (both use [`project_element`]).

use rayon::prelude::*;

use super::cubic::{CubicCoefficients, LocalFrame, Material, MONOMIALS};
use super::error::SpacetimeError;
use super::mesh::{ElementField, SpacetimeMesh};
use super::record::ElementRecord;
use crate::tensor::{solve_many, Tensor};

/// Five-point Gauss–Legendre rule on [0, 1]: nodes and weights.
pub(crate) const GAUSS5: [(f64, f64); 5] = [
    (0.046_910_077_030_668_0, 0.118_463_442_528_094_5),
    (0.230_765_344_947_158_5, 0.239_314_335_249_683_2),
    (0.5, 0.284_444_444_444_444_4),
    (0.769_234_655_052_841_5, 0.239_314_335_249_683_2),
    (0.953_089_922_969_332, 0.118_463_442_528_094_5),
];

/// Quadrature points (barycentric weights of corners 1, 2, 3) and weights (summing to 1) on a
/// tetrahedron: the collapsed-coordinate product of 5-point Gauss rules, exact for polynomials
/// of degree 6 (a cubic times a cubic: the L2 projection's mass matrix) — the collapse adds
/// degree 3 in the first coordinate, within the rule's degree 9.
fn tet_quadrature() -> Vec<([f64; 3], f64)> {
    let mut q = Vec::with_capacity(125);
    for &(a, wa) in &GAUSS5 {
        for &(b, wb) in &GAUSS5 {
            for &(c, wc) in &GAUSS5 {
                let l1 = a;
                let l2 = b * (1.0 - a);
                let l3 = c * (1.0 - a) * (1.0 - b);
                // d(l1, l2, l3) = (1 − a)² (1 − b) da db dc; the reference volume is 1/6.
                q.push(([l1, l2, l3], 6.0 * wa * wb * wc * (1.0 - a) * (1.0 - a) * (1.0 - b)));
            }
        }
    }
    q
}

/// [`tet_quadrature`], built once (every element's projection uses it).
static TET_QUADRATURE: std::sync::LazyLock<Vec<([f64; 3], f64)>> = std::sync::LazyLock::new(tet_quadrature);

/// Values of the 20 monomials at local point `q`.
fn monomials(q: [f64; 3]) -> [f64; 20] {
    let mut m = [0.0; 20];
    for (k, e) in MONOMIALS.iter().enumerate() {
        m[k] = q[0].powi(e[0] as i32) * q[1].powi(e[1] as i32) * q[2].powi(e[2] as i32);
    }
    m
}

/// The L2 projection of `field` onto the cubic monomials of an element with corners `p`, in
/// the element's bounding-box frame.
pub fn project_element(
    p: [[f64; 3]; 4],
    field: &(impl Fn([f64; 3]) -> [f64; 2] + Sync),
) -> (LocalFrame, CubicCoefficients) {
    let frame = LocalFrame::bounding(&p);
    let mut mass = vec![0.0; 400];
    let mut rhs = [[0.0; 20]; 2];
    for &(l, w) in TET_QUADRATURE.iter() {
        let l0 = 1.0 - l[0] - l[1] - l[2];
        let x: [f64; 3] =
            std::array::from_fn(|k| l0 * p[0][k] + l[0] * p[1][k] + l[1] * p[2][k] + l[2] * p[3][k]);
        let m = monomials(frame.local(x));
        let f = field(x);
        // The upper triangle of the symmetric mass matrix; mirrored below.
        for i in 0..20 {
            let wm = w * m[i];
            for j in i..20 {
                mass[i * 20 + j] += wm * m[j];
            }
            rhs[0][i] += wm * f[0];
            rhs[1][i] += wm * f[1];
        }
    }
    for i in 0..20 {
        for j in 0..i {
            mass[i * 20 + j] = mass[j * 20 + i];
        }
    }
    let mass = Tensor::from_vec(&[20, 20], mass).expect("20 × 20");
    // The mass matrix of 20 monomials on a non-degenerate element is SPD; one factorisation
    // serves both components.
    let x = solve_many("element mass matrix", &mass, &[&rhs[0], &rhs[1]]).expect("non-degenerate element");
    (frame, std::array::from_fn(|k| [x[0][k], x[1][k]]))
}

/// A structured spacetime mesh over `[0, size[0]] × [0, size[1]] × [0, duration]`: `nx × ny`
/// squares, each split into two triangles, extruded through `nt` equal time layers, each
/// prism split into three tetrahedra (`6 nx ny nt` elements), sorted by lowest time. Fields
/// are zero and the one material is `material`.
pub fn structured_mesh(
    nx: usize,
    ny: usize,
    nt: usize,
    size: [f64; 2],
    duration: f64,
    material: Material,
) -> SpacetimeMesh {
    let layer = (nx + 1) * (ny + 1);
    let mut vertices = Vec::with_capacity(layer * (nt + 1));
    for k in 0..=nt {
        for j in 0..=ny {
            for i in 0..=nx {
                vertices.push([
                    size[0] * i as f64 / nx as f64,
                    size[1] * j as f64 / ny as f64,
                    duration * k as f64 / nt as f64,
                ]);
            }
        }
    }
    let mut tets = Vec::with_capacity(6 * nx * ny * nt);
    for k in 0..nt {
        for j in 0..ny {
            for i in 0..nx {
                let v = |di: usize, dj: usize| (j + dj) * (nx + 1) + i + di;
                for tri in [[v(0, 0), v(1, 0), v(1, 1)], [v(0, 0), v(1, 1), v(0, 1)]] {
                    // Prism split by the global order of the base triangle's vertices: neighbours
                    // sharing a quadrilateral face pick the same diagonal.
                    let mut t = tri;
                    t.sort_unstable();
                    let [a, b, c] = t.map(|x| (x + k * layer) as u32);
                    let up = layer as u32;
                    tets.push([a, b, c, c + up]);
                    tets.push([a, b, b + up, c + up]);
                    tets.push([a, a + up, b + up, c + up]);
                }
            }
        }
    }
    // Positively oriented, as VTK counts it (vtkTetra: 0, 1, 2 turn counter-clockwise seen
    // from 3; `vtkMeshQuality` gives the others negative volume): half the split prisms' come
    // out the other way round.
    for t in &mut tets {
        let p = t.map(|i| vertices[i as usize]);
        if super::mesh::six_volume(p) < 0.0 {
            t.swap(1, 2);
        }
    }
    let zero = ElementField {
        frame: LocalFrame { centre: [0.0; 3], extent: [1.0; 3] },
        material: 0,
        coefficients: [[0.0; 2]; 20],
    };
    let mut mesh =
        SpacetimeMesh { vertices, tets, fields: vec![zero; 6 * nx * ny * nt], materials: vec![material] };
    mesh.sort_by_lowest_time();
    mesh
}

/// Fills every element with the L2 projection of `field` (in parallel).
pub fn project_field(mesh: &mut SpacetimeMesh, field: &(impl Fn([f64; 3]) -> [f64; 2] + Sync)) {
    let corners: Vec<[[f64; 3]; 4]> = (0..mesh.tets.len()).map(|e| mesh.corners(e)).collect();
    let projected: Vec<(LocalFrame, CubicCoefficients)> =
        corners.par_iter().map(|&p| project_element(p, field)).collect();
    for (f, (frame, c)) in mesh.fields.iter_mut().zip(projected) {
        f.frame = frame;
        f.coefficients = c;
    }
}

/// A Gaussian pulse `g(ξ) = exp(−ξ² / (2σ²))`.
fn gaussian(xi: f64, sigma: f64) -> f64 {
    (-xi * xi / (2.0 * sigma * sigma)).exp()
}

/// A plane pressure pulse travelling along the unit direction `d` plus a shear pulse along
/// `e`, each an exact solution of linear elastodynamics in the homogeneous `material`:
/// `u = A d g(d·x − c_p t − s_p) + B e⊥ g(e·x − c_s t − s_s)`.
pub fn crossing_pulses(material: Material, size: [f64; 2]) -> impl Fn([f64; 3]) -> [f64; 2] + Sync {
    let (cp, cs) = (material.p_wave_speed(), material.s_wave_speed());
    let d = [0.8, 0.6];
    let e = [-0.6, 0.8];
    let sigma = 0.08 * size[0].max(size[1]);
    let amp = 0.01 * size[0].max(size[1]);
    move |p: [f64; 3]| {
        let xi_p = d[0] * p[0] + d[1] * p[1] - cp * p[2] - 0.1 * size[0];
        let xi_s = e[0] * (p[0] - size[0]) + e[1] * p[1] - cs * p[2] + 0.1 * size[0];
        let gp = amp * gaussian(xi_p, sigma);
        let gs = 0.7 * amp * gaussian(xi_s, sigma);
        // Shear pulse polarised across its direction: e⊥ = (−e_y, e_x).
        [d[0] * gp - e[1] * gs, d[1] * gp + e[0] * gs]
    }
}

/// The material of the `pulses` data set.
pub const PULSES_MATERIAL: Material = Material { lambda: 2.0, mu: 1.0, density: 1.0 };

/// Cells per axis of the `pulses` data set of about `elements` tetrahedra (`6 k³`).
fn pulses_cells(elements: usize) -> usize {
    ((elements as f64 / 6.0).cbrt().round() as usize).max(1)
}

/// The data set of `galerkin spacetime gen --generate pulses`: the unit square over a time
/// span that lets both pulses cross it, with about `elements` tetrahedra.
pub fn pulses(elements: usize) -> SpacetimeMesh {
    let k = pulses_cells(elements);
    let size = [1.0, 1.0];
    let mut mesh = structured_mesh(k, k, k, size, 1.0 / PULSES_MATERIAL.p_wave_speed(), PULSES_MATERIAL);
    project_field(&mut mesh, &crossing_pulses(PULSES_MATERIAL, size));
    mesh
}

/// [`pulses`] streamed time layer by time layer in ascending lowest time — the same records,
/// never more than one layer in memory — for data sets larger than memory. `progress` is told
/// the elements done after each layer.
pub fn stream_pulses(
    elements: usize,
    sink: &mut dyn FnMut(&ElementRecord) -> Result<(), SpacetimeError>,
    progress: &mut dyn FnMut(u64),
) -> Result<(), SpacetimeError> {
    let k = pulses_cells(elements);
    let size = [1.0, 1.0];
    let duration = 1.0 / PULSES_MATERIAL.p_wave_speed();
    let field = crossing_pulses(PULSES_MATERIAL, size);
    let mut done = 0u64;
    for layer in 0..k {
        // One layer of the structured mesh, its times set by the same formula as
        // `structured_mesh` uses for the whole (so the values are bit-identical).
        let mut mesh = structured_mesh(k, k, 1, size, duration, PULSES_MATERIAL);
        for v in &mut mesh.vertices {
            let local = if v[2] > 0.0 { 1 } else { 0 };
            v[2] = duration * (layer + local) as f64 / k as f64;
        }
        project_field(&mut mesh, &field);
        for e in 0..mesh.tets.len() {
            sink(&ElementRecord::of(&mesh, e))?;
        }
        done += mesh.tets.len() as u64;
        progress(done);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spacetime::cubic::evaluate;

    #[test]
    fn quadrature_integrates_degree_six_exactly() {
        // ∫ over the unit tetrahedron of x^a y^b z^c = a! b! c! / (a + b + c + 3)!.
        let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
        let q = tet_quadrature();
        for (a, b, c) in [(0, 0, 0), (2, 2, 2), (6, 0, 0), (3, 2, 1), (1, 4, 1)] {
            let got: f64 = q.iter().map(|(l, w)| w / 6.0 * l[0].powi(a) * l[1].powi(b) * l[2].powi(c)).sum();
            let want = fact(a as u32) * fact(b as u32) * fact(c as u32) / fact((a + b + c + 3) as u32);
            assert!((got - want).abs() < 1e-15, "{a} {b} {c}: {got} vs {want}");
        }
    }

    #[test]
    fn a_cubic_field_is_projected_exactly() {
        let material = Material { lambda: 1.0, mu: 1.0, density: 1.0 };
        let mut mesh = structured_mesh(2, 2, 2, [1.0, 1.0], 1.0, material);
        let f = |p: [f64; 3]| [p[0] * p[1] * p[2] - p[2] * p[2], 2.0 * p[0].powi(3) + p[1]];
        project_field(&mut mesh, &f);
        mesh.validate().unwrap();
        for e in 0..mesh.tets.len() {
            let c = mesh.corners(e);
            let x = [
                0.25 * (c[0][0] + c[1][0] + c[2][0] + c[3][0]),
                0.25 * (c[0][1] + c[1][1] + c[2][1] + c[3][1]),
                0.25 * (c[0][2] + c[1][2] + c[2][2] + c[3][2]),
            ];
            let got =
                evaluate(&mesh.fields[e].frame, &material, &mesh.fields[e].coefficients, x).displacement;
            let want = f(x);
            assert!(
                (got[0] - want[0]).abs() < 1e-11 && (got[1] - want[1]).abs() < 1e-11,
                "{got:?} vs {want:?}"
            );
        }
    }

    #[test]
    fn streamed_pulses_are_the_in_memory_records() {
        let mesh = pulses(1500);
        let mut streamed = Vec::new();
        stream_pulses(
            1500,
            &mut |r| {
                streamed.push(*r);
                Ok(())
            },
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(streamed.len(), mesh.tets.len());
        for (e, r) in streamed.iter().enumerate() {
            assert_eq!(*r, ElementRecord::of(&mesh, e), "element {e}");
        }
    }

    #[test]
    fn structured_meshes_are_valid_and_sorted() {
        let m = structured_mesh(3, 2, 4, [2.0, 1.0], 1.0, Material { lambda: 1.0, mu: 1.0, density: 1.0 });
        assert_eq!(m.tets.len(), 6 * 3 * 2 * 4);
        m.validate().unwrap();
        assert!((0..m.tets.len() - 1).all(|e| m.lowest_time(e) <= m.lowest_time(e + 1)));
        // Total spacetime volume = 2 × 1 × 1, every tetrahedron positively oriented (VTK's
        // convention, what the .vtu writer hands ParaView).
        let six: Vec<f64> =
            (0..m.tets.len()).map(|e| crate::spacetime::mesh::six_volume(m.corners(e))).collect();
        assert!(
            six.iter().all(|&v| v > 0.0),
            "negative volumes: {}",
            six.iter().filter(|&&v| v <= 0.0).count()
        );
        assert!((six.iter().sum::<f64>() / 6.0 - 2.0).abs() < 1e-12);
    }

    #[test]
    fn tent_pitched_scenarios_are_positively_oriented_too() {
        use crate::spacetime::scenario::{generate, Scenario};
        for s in Scenario::ALL {
            let m = generate(s, 3000);
            let negative = (0..m.tets.len())
                .filter(|&e| crate::spacetime::mesh::six_volume(m.corners(e)) <= 0.0)
                .count();
            assert_eq!(
                negative,
                0,
                "{}: {negative} of {} tetrahedra not positively oriented",
                s.name(),
                m.tets.len()
            );
        }
    }
}
