//! The volume tensor of seed 000 Eq. 7: every cell's volume as a homogeneous polynomial of
//! degree d in the geometry vector g, stored as the reduction core's sparse tensor so that it
//! can be premultiplied. Shared by the fluid (`crate::fluid::operators`) and the reduction
//! core's synthetic benchmarks.

use super::SimplexMesh;
use crate::tensor::SparseTensor;

fn factorial(n: usize) -> f64 {
    (1..=n).product::<usize>() as f64
}

fn permutation_parity(p: &[usize]) -> f64 {
    let mut inversions = 0;
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            if p[i] > p[j] {
                inversions += 1;
            }
        }
    }
    if inversions % 2 == 0 {
        1.0
    } else {
        -1.0
    }
}

/// The monomials of `d!·vol = det[[1, x₀], …, [1, x_d]]`: each `sign · Π_k coord_k(vertex a_k)`
/// for distinct local vertices `a_1 … a_d` (the remaining vertex r fills the ones column;
/// the sign is that of the permutation `(r, a_1, …, a_d)`).
pub fn volume_monomials(dim: usize) -> Vec<(f64, Vec<usize>)> {
    let mut out = Vec::new();
    let n = dim + 1;
    let mut stack: Vec<Vec<usize>> = vec![vec![]];
    while let Some(prefix) = stack.pop() {
        if prefix.len() == dim {
            let r = (0..n).find(|v| !prefix.contains(v)).expect("one vertex left");
            let mut perm = vec![r];
            perm.extend(&prefix);
            out.push((permutation_parity(&perm), prefix));
            continue;
        }
        for v in 0..n {
            if !prefix.contains(&v) {
                let mut p = prefix.clone();
                p.push(v);
                stack.push(p);
            }
        }
    }
    out.sort_by(|a, b| a.1.cmp(&b.1));
    out
}

/// The volume tensor V (Eq. 7) of `mesh`: shape `[d·n_c, d·n_c, G, …, G]` with d geometry
/// axes (G = d·n_v), declared symmetric, so that `V ⊗₁ u ⊗₂ g ⋯ ⊗_{d+1} g = vol(c)·u_c` in
/// every cell. Each monomial `x_a y_b (z_c)` is stored once with coefficient
/// `sign / (d!)²` (its d! permutations add up to `sign/d!`).
pub fn volume_tensor(mesh: &SimplexMesh) -> SparseTensor {
    let d = mesh.dim();
    let (nc, nv) = (mesh.cell_count(), mesh.vertex_count());
    let mut shape = vec![d * nc, d * nc];
    shape.extend(std::iter::repeat_n(d * nv, d));
    let axes: Vec<usize> = (2..2 + d).collect();
    let mut v = SparseTensor::new(&shape).with_symmetric_axes(&axes).expect("d equal geometry axes");
    let monomials = volume_monomials(d);
    let scale = 1.0 / (factorial(d) * factorial(d));
    let mut index = vec![0usize; 2 + d];
    for c in 0..nc {
        let cell = mesh.cell(c);
        for k in 0..d {
            index[0] = d * c + k;
            index[1] = d * c + k;
            for (sign, verts) in &monomials {
                for (axis, &a) in verts.iter().enumerate() {
                    index[2 + axis] = d * cell[a] as usize + axis;
                }
                v.push(&index, sign * scale);
            }
        }
    }
    v
}

/// The volume enclosed by the boundary faces at geometry `g`: `(1/3) Σ_faces c_f · A_f n_f`
/// (divergence theorem; equal to the sum of cell volumes for any interior).
pub fn enclosed_volume(mesh: &super::SimplexMesh, topo: &super::Topology, g: &[f64]) -> f64 {
    let d = mesh.dim();
    let mut v = 0.0;
    for &f in topo.boundary_faces() {
        let [c, _] = topo.face_cells(f as usize);
        let l = topo.face_local(f as usize)[0] as usize;
        let p = mesh.cell_points_at(g, c as usize);
        let n = super::geometry::face_area_normal(d, &p, l);
        let x = super::geometry::face_centroid(&p, l);
        v += (0..d).map(|k| x[k] * n[k]).sum::<f64>() / d as f64;
    }
    v
}
