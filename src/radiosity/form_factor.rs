//! Form factors at face centroids (seed 000 Eq. 15), the CPU f64 path and reference.
//!
//! `F_ij` is the fraction of the light leaving face `i` that reaches face `j` (so that
//! `bᵢ = eᵢ + ρᵢ Σⱼ F_ij bⱼ`, Eq. 14), sampled at the centroids:
//!
//! ```text
//! F_ij = s_ij s_ji Vis(i, j) / (4π r_ij² Aᵢ),   s_ij = nᵢ·(cⱼ − cᵢ),
//! r_ij = |cᵢ − cⱼ|² + (Lᵢ + Lⱼ) / (16π)          (NearField::Regularised, the default)
//! r_ij = |cᵢ − cⱼ|²                              (NearField::Eq15, as printed)
//! ```
//!
//! with `nᵢ` the *unnormalised* normal of Table 2 (`|nᵢ| = 2Aᵢ`) and `Lᵢ` the sum of face
//! `i`'s squared edge lengths.
//!
//! **The constant.** Eq. 15 as printed has no 4 in the denominator; with unnormalised normals
//! it is then 4 times the point-to-area form factor `Aⱼ cos θᵢ cos θⱼ / (π r²)`, and rows of a
//! closed room would sum to 4. The 4 is checked by the closed forms in the tests (parallel unit
//! squares one apart: 0.1998; perpendicular unit squares sharing an edge: 0.2000),
//! reciprocity `Aᵢ F_ij = Aⱼ F_ji`, and rows summing to 1 in a closed box.
//!
//! **The near field.** Point sampling diverges for neighbours: two faces meeting at a corner
//! have centroids a fraction of a cell apart, and on the generated scene's 4,974 faces Eq. 15
//! as printed gives single entries up to 4.6 and 320 rows summing above 1.1 — `ρF` then has
//! rows above 1 and Eq. 14's iteration diverges. The default adds `(Lᵢ + Lⱼ)/(16π)` to the
//! squared distance (for the grid's right triangles, `(Aᵢ + Aⱼ)/(2π)`: the disk
//! approximation of Wallace et al. 1989, made symmetric). It keeps everything Table 2 needs:
//! `r` is still quadratic in `g` (one more sparse tensor term), symmetric (`r_ij = r_ji`, so
//! reciprocity holds exactly), it bounds every entry by ½ (largest on the scene: 0.15, the
//! largest row sum 1.014), and it vanishes as the mesh is refined (the closed forms are met at
//! the same rate).
//!
//! `Vis(i, j)` is 1 when the faces face each other (both scaled cosines above a relative
//! 10⁻⁹, so that back-to-back pairs, whose cosine product is also positive, get 0) and the
//! segment between the centroids crosses no other face ([`Bvh::occluded`]); `F_ii = 0`.

use glam::DVec3;
use rayon::prelude::*;

use super::bvh::Bvh;
use super::mesh::{FaceGeometry, SceneMesh};

/// Relative threshold on the scaled cosines below which two faces do not face each other.
pub const FACING_EPSILON: f64 = 1e-9;

/// How the squared distance treats near pairs (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NearField {
    /// `r_ij = |cᵢ − cⱼ|² + (Lᵢ + Lⱼ)/(16π)`: bounded entries, converging to Eq. 15.
    #[default]
    Regularised,
    /// `r_ij = |cᵢ − cⱼ|²`, Eq. 15 as printed (for the closed-form tests).
    Eq15,
}

impl NearField {
    /// The squared distance `r_ij` of Table 2 from `d = cⱼ − cᵢ` and the two faces' sums of
    /// squared edge lengths.
    #[inline]
    pub fn squared_distance(self, d: DVec3, edge_squares_i: f64, edge_squares_j: f64) -> f64 {
        let r = d.length_squared();
        match self {
            NearField::Regularised => r + (edge_squares_i + edge_squares_j) / (16.0 * std::f64::consts::PI),
            NearField::Eq15 => r,
        }
    }
}

/// The scaled cosines `s_ij = nᵢ·d` and `s_ji = −nⱼ·d` of Table 2 from `d = cⱼ − cᵢ` and the
/// two faces' normals.
#[inline]
pub fn scaled_cosines_of(d: DVec3, normal_i: DVec3, normal_j: DVec3) -> (f64, f64) {
    (normal_i.dot(d), -normal_j.dot(d))
}

/// The scaled cosines `s_ij = nᵢ·(cⱼ − cᵢ)` and `s_ji = nⱼ·(cᵢ − cⱼ)` of Table 2 (the
/// squared distance is [`squared_distance`]).
pub fn scaled_cosines(g: &FaceGeometry, i: usize, j: usize) -> (f64, f64) {
    scaled_cosines_of(g.centroids[j] - g.centroids[i], g.normals[i], g.normals[j])
}

/// The squared distance `r_ij` of Table 2 under `near`.
pub fn squared_distance(g: &FaceGeometry, i: usize, j: usize, near: NearField) -> f64 {
    near.squared_distance(g.centroids[j] - g.centroids[i], g.edge_squares[i], g.edge_squares[j])
}

/// Whether faces `i ≠ j` face each other (the part of `Vis(i, j)` that needs no ray).
pub fn facing(g: &FaceGeometry, i: usize, j: usize) -> bool {
    if i == j {
        return false;
    }
    let (sij, sji) = scaled_cosines(g, i, j);
    let r = (g.centroids[j] - g.centroids[i]).length();
    sij > FACING_EPSILON * g.normals[i].length() * r && sji > FACING_EPSILON * g.normals[j].length() * r
}

/// `F_ij` for `Vis(i, j) = 1`.
pub fn unoccluded_form_factor(g: &FaceGeometry, i: usize, j: usize, near: NearField) -> f64 {
    let (sij, sji) = scaled_cosines(g, i, j);
    let r = squared_distance(g, i, j, near);
    sij * sji / (4.0 * std::f64::consts::PI * r * r * g.areas[i])
}

/// `Vis(i, j)`: facing and not occluded.
pub fn visible(mesh_bvh: &Bvh, g: &FaceGeometry, i: usize, j: usize) -> bool {
    facing(g, i, j) && !mesh_bvh.occluded(g.centroids[i], g.centroids[j], [i as u32, j as u32])
}

/// A dense `n × n` matrix, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct FormFactors {
    /// Number of faces.
    pub n: usize,
    /// `F_ij` at `i·n + j` (the paper's unrolled `p_k`, `k = ni + j`).
    pub values: Vec<f64>,
}

impl FormFactors {
    /// Row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.n..(i + 1) * self.n]
    }

    /// `F_ij`.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.values[i * self.n + j]
    }
}

/// The BVH over a mesh's faces.
pub fn bvh_of(mesh: &SceneMesh) -> Bvh {
    Bvh::new((0..mesh.len()).map(|i| mesh.corners(i)).collect())
}

/// Every `F_ij` with visibility (rows in parallel; each unordered pair's ray is cast once).
pub fn form_factors(mesh: &SceneMesh, near: NearField) -> FormFactors {
    let n = mesh.len();
    let g = mesh.geometry();
    let vis = visible_pairs(mesh, &g);
    let mut values = vec![0.0; n * n];
    for (i, row) in vis.iter().enumerate() {
        for &j in row {
            let j = j as usize;
            values[i * n + j] = unoccluded_form_factor(&g, i, j, near);
            values[j * n + i] = unoccluded_form_factor(&g, j, i, near);
        }
    }
    FormFactors { n, values }
}

/// The visible pairs `i < j`, row by row (rows in parallel; each unordered pair's segment
/// is cast once).
pub fn visible_pairs(mesh: &SceneMesh, g: &FaceGeometry) -> Vec<Vec<u32>> {
    let n = mesh.len();
    let bvh = bvh_of(mesh);
    (0..n)
        .into_par_iter()
        .map(|i| (i + 1..n).filter(|&j| visible(&bvh, g, i, j)).map(|j| j as u32).collect())
        .collect()
}

/// `Vis(i, j)` of every pair at `k = n·i + j` (1 or 0): the visibility input `v` of Table 2.
pub fn visibility(mesh: &SceneMesh) -> Vec<f64> {
    let n = mesh.len();
    let rows = visible_pairs(mesh, &mesh.geometry());
    let mut v = vec![0.0; n * n];
    for (i, row) in rows.iter().enumerate() {
        for &j in row {
            v[i * n + j as usize] = 1.0;
            v[j as usize * n + i] = 1.0;
        }
    }
    v
}

/// Form factors between two face sets of one mesh without visibility (for closed forms):
/// the area-weighted `F_{A→B} = Σ_{i∈A} Aᵢ Σ_{j∈B} F_ij / Σ_{i∈A} Aᵢ`.
pub fn patch_form_factor(mesh: &SceneMesh, a: &[usize], b: &[usize], near: NearField) -> f64 {
    let g = mesh.geometry();
    let total: f64 = a.iter().map(|&i| g.areas[i]).sum();
    let sum: f64 = a
        .par_iter()
        .map(|&i| {
            g.areas[i]
                * b.iter()
                    .filter(|&&j| facing(&g, i, j))
                    .map(|&j| unoccluded_form_factor(&g, i, j, near))
                    .sum::<f64>()
        })
        .sum();
    sum / total
}

/// The unit normal of face `i` (for shading).
pub fn unit_normal(g: &FaceGeometry, i: usize) -> DVec3 {
    g.normals[i] / (2.0 * g.areas[i])
}
