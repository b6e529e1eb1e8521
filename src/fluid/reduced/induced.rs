//! The induced flux as a tensor (beyond the paper: §6.2 replays stored ĥ; this lets a reduced
//! model be driven by motions that were never simulated).
//!
//! The full solver's induced flux of face i over a frame, `h_i = swept_volume(g_t, g_{t+1}) / Δt`
//! (Eq. 11 integrated exactly by Simpson's rule, [`crate::mesh::geometry::swept_volume`]), is a
//! homogeneous polynomial of degree d in the face's vertex coordinates at both ends of the frame:
//! the area normal is degree d − 1, the centroid's displacement linear. So with the stacked
//! geometry `γ = [g_t; g_{t+1}]` (2G entries) it is one tensor `H[face, γ, …, γ]` with d
//! symmetric γ axes, `h = H ⊗₂ γ ⋯ ⊗_{d+1} γ`, and reduces like the volume tensor:
//! `Ĥ = B_hᵀ H ⊗ B_γ ⋯ ⊗ B_γ` with `B_γ = diag(B_g, B_g)`.
//!
//! Its entries come from the full solver's own `swept_volume` by polarization — the symmetric
//! d-linear form of a homogeneous polynomial q of degree d is
//! `T(x₁, …, x_d) = (1 / (d! 2^d)) Σ_{ε ∈ {±1}^d} ε₁⋯ε_d q(ε₁x₁ + ⋯ + ε_d x_d)` — evaluated
//! on unit vectors of a face's 2d² local coordinates, so there is one implementation of the
//! induced flux and the tensor is tested against it. The form depends only on the local
//! coordinates and the face's orientation in its cell, so it is computed once per orientation
//! (d + 1 of them) and placed at every face's global coordinates.

use crate::mesh::geometry::{swept_volume, Point};
use crate::mesh::{SimplexMesh, Topology};
use crate::tensor::SparseTensor;

/// Entries of a face's polarized form below this (relative to the face's largest) are
/// rounding of exact zeros and are dropped.
const ZERO: f64 = 1e-13;

/// The induced-flux tensor `H` of `mesh` (see the module docs): shape `[n_f, 2G, …, 2G]`, the
/// last d axes one symmetric group, scaled by 1/`frame_time`.
pub fn induced_flux_tensor(mesh: &SimplexMesh, topo: &Topology, frame_time: f64) -> SparseTensor {
    let d = mesh.dim();
    let big_g = d * mesh.vertex_count();
    let mut shape = vec![topo.face_count()];
    shape.extend(std::iter::repeat_n(2 * big_g, d));
    let axes: Vec<usize> = (1..=d).collect();
    let mut h = SparseTensor::new(&shape).with_symmetric_axes(&axes).expect("d equal γ axes");
    let nl = 2 * d * d;
    let tuples = sorted_tuples(nl, d);
    let signs: Vec<Vec<f64>> = (0..1usize << d)
        .map(|m| (0..d).map(|j| if m >> j & 1 == 1 { -1.0 } else { 1.0 }).collect())
        .collect();
    let norm = 1.0 / ((1..=d).product::<usize>() as f64 * (1u32 << d) as f64) / frame_time;
    // The polarized form of a face depends only on its local coordinates and on which vertex
    // of its cell it is opposite (the orientation), not on where the face is: compute it once
    // per local index l (d + 1 forms of 2d² coordinates, instead of one per face).
    let local: Vec<Vec<(usize, f64)>> = (0..=d)
        .map(|l| {
            let face: Vec<usize> = (0..=d).filter(|&a| a != l).collect();
            let q = |x: &[f64]| -> f64 {
                let mut p0 = vec![[0.0; 3]; d + 1];
                let mut p1 = vec![[0.0; 3]; d + 1];
                for (j, &a) in face.iter().enumerate() {
                    for k in 0..d {
                        p0[a][k] = x[j * d + k];
                        p1[a][k] = x[d * d + j * d + k];
                    }
                }
                swept_volume(d, &p0 as &[Point], &p1, l)
            };
            let mut x = vec![0.0; nl];
            let values: Vec<f64> = tuples
                .iter()
                .map(|t| {
                    let mut sum = 0.0;
                    for s in &signs {
                        x.iter_mut().for_each(|v| *v = 0.0);
                        for (j, &i) in t.iter().enumerate() {
                            x[i] += s[j];
                        }
                        sum += s.iter().product::<f64>() * q(&x);
                    }
                    sum * norm
                })
                .collect();
            let largest = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            values.into_iter().enumerate().filter(|(_, v)| v.abs() > ZERO * largest).collect()
        })
        .collect();
    let mut index = vec![0usize; d + 1];
    for f in 0..topo.face_count() {
        let [c, _] = topo.face_cells(f);
        let l = topo.face_local(f)[0] as usize;
        let cell = mesh.cell(c as usize);
        // The face's vertices (the cell's, without l), in the cell's order.
        let face: Vec<usize> = (0..=d).filter(|&a| a != l).collect();
        index[0] = f;
        for &(t, v) in &local[l] {
            for (j, &i) in tuples[t].iter().enumerate() {
                // Local coordinate i: time τ = i / d², face vertex (i mod d²) / d, axis i mod d.
                let (tau, rest) = (i / (d * d), i % (d * d));
                let vertex = cell[face[rest / d]] as usize;
                index[1 + j] = tau * big_g + d * vertex + rest % d;
            }
            h.push(&index, v);
        }
    }
    h
}

/// Sorted index tuples `i₁ ≤ … ≤ i_d` over `0..m`.
pub(crate) fn sorted_tuples(m: usize, d: usize) -> Vec<Vec<usize>> {
    let mut out = vec![vec![]];
    for _ in 0..d {
        let mut next = Vec::new();
        for t in out {
            let start = t.last().copied().unwrap_or(0);
            for i in start..m {
                let mut u = t.clone();
                u.push(i);
                next.push(u);
            }
        }
        out = next;
    }
    out
}
