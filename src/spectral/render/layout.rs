//! A mesh as the spectral shaders read it (`spectral_element.glsl`): the specialization
//! constants of its bases and shape, its geometry points and its fields' coefficients, padded
//! per element.

use super::super::basis::{NodeSet, MAX_ORDER};
use super::super::mesh::SpectralMesh;

/// The specialization constants of `spectral_element.glsl` for `mesh`'s two bases: per basis
/// its kind (0 Lagrange, 1 Bernstein) and order, then its nodes and barycentric weights as f32
/// bits, each padded to [`MAX_ORDER`] + 1; then the reference dimension. Compiled into the pipelines, the evaluation loops
/// unroll and the nodes fold into the code instead of being read per fragment. Last, whether the two
/// bases are one.
pub fn basis_specialization(mesh: &SpectralMesh) -> Vec<u32> {
    let mut v = Vec::with_capacity(4 * (MAX_ORDER + 2));
    for b in [&mesh.basis, &mesh.geometry] {
        v.push(u32::from(b.set == NodeSet::Bernstein));
        v.push(b.order as u32);
        for list in [&b.nodes, &b.weights] {
            v.extend((0..=MAX_ORDER).map(|k| (list.get(k).copied().unwrap_or(0.0) as f32).to_bits()));
        }
    }
    // Id 56: the reference dimension.
    v.push(mesh.shape.dim());
    // Id 57: field and geometry share one basis (isoparametric elements), so a fragment that
    // needs both evaluates the 1D bases once.
    v.push(u32::from(mesh.basis == mesh.geometry));
    // Id 58: rational cells (homogeneous points and coefficients, see `geometry_points`).
    v.push(u32::from(mesh.weights.is_some()));
    // Id 59: Lagrange triangles and tetrahedra (spectral_simplex.glsl).
    v.push(u32::from(mesh.shape.is_simplex()));
    v
}

/// The geometry as `spectral_element.glsl` reads it: (x, y, z, 0) per node, or for rational
/// cells the homogeneous (w x, w y, w z, w).
pub fn geometry_points(mesh: &SpectralMesh) -> Vec<[f32; 4]> {
    match &mesh.weights {
        None => mesh.points.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, 0.0]).collect(),
        Some(w) => mesh
            .points
            .iter()
            .zip(w)
            .map(|(p, &w)| [(w * p[0]) as f32, (w * p[1]) as f32, (w * p[2]) as f32, w as f32])
            .collect(),
    }
}

/// The coefficients of `field` at `step` as `spectral_element.glsl` reads them: f32 (times the
/// node's weight for rational cells), each
/// element's (n + 1)² padded with zeros to a multiple of 4.
pub fn padded_values(mesh: &SpectralMesh, field: usize, step: usize) -> Vec<f32> {
    let per = mesh.values_per_element();
    let stride = per.div_ceil(4) * 4;
    let mut out = vec![0.0f32; stride * mesh.elements()];
    for (e, chunk) in mesh.fields[field].steps[step].chunks_exact(per).enumerate() {
        let weights = mesh.element_weights(e);
        for (k, (o, &v)) in out[e * stride..].iter_mut().zip(chunk).enumerate() {
            *o = weights.map_or(v, |w| w[k] * v) as f32;
        }
    }
    out
}

/// The coefficients of several `fields` at `step`, element by element: each element's padded
/// run ([`padded_values`]) of every field in turn — the field slots of `spectral_element.glsl`
/// (`SPECTRAL_FIELDS`), slot k being `fields[k]`.
pub fn padded_slots(mesh: &SpectralMesh, fields: &[usize], step: usize) -> Vec<f32> {
    let runs: Vec<Vec<f32>> = fields.iter().map(|&f| padded_values(mesh, f, step)).collect();
    let stride = mesh.values_per_element().div_ceil(4) * 4;
    let mut out = Vec::with_capacity(runs.len() * stride * mesh.elements() + 4);
    for e in 0..mesh.elements() {
        for run in &runs {
            out.extend_from_slice(&run[e * stride..(e + 1) * stride]);
        }
    }
    out
}
