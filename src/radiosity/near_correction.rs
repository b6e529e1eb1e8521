//! The exact near field in the training solves (issue 28; seed 000 §8.2–8.3, Table 2).
//!
//! Table 2's chain computes centroid form factors (Eq. 15 with the regularised near field,
//! [`super::form_factor`]): a product of quadratic forms in `g`, which is what makes it
//! reducible, and biased low where faces meet. The exact polygon form factor
//! ([`super::near_field::exact_form_factor`]) is no tensor contraction of `g`, so it enters as a
//! *precomputed correction*: for every training configuration `t`,
//!
//! ```text
//! ΔF_t(i, j) = F_exact(i, j) − F_centroid(i, j)    visible pairs within `reach` face diameters
//! ```
//!
//! The training solves use `F_centroid + ΔF_t`, so `B_b` is built from the corrected radiosity,
//! and the model carries it through the operator correction
//! ([`super::operator_correction`]): the exact operator projected at each training
//! configuration is made from these same form factors, so at a training configuration the
//! reduced operator has the exact near field, and between them the blend of the training
//! configurations' (Eq. 17's weights).
//!
//! Storage: `ΔF_t` is kept per configuration for the pairs `i < j` only (`ΔF_ji = ΔF_ij Aᵢ/Aⱼ`,
//! since both form factors obey reciprocity), as `(k = n·i + j, f32)`: eight bytes a near pair
//! (2.7 MB a configuration at 4,876 faces). f32 rounds the correction by 6·10⁻⁸ of itself, far
//! below the accuracy sought; the training solve applies the rounded value, so what the
//! operator correction regenerates is exactly what the training radiosity was solved with.

use std::sync::Arc;

use glam::DVec3;
use rayon::prelude::*;

use super::form_factor::FormFactors;
use super::mesh::FaceGeometry;
use super::near_field::{exact_form_factor, is_near};

/// `ΔF(i, j)` at `k = n·i + j` for the pairs `i < j` that have one (see the module documentation).
pub type NearCorrection = Arc<[(u32, f32)]>;

/// `ΔF = F_exact − F` for the visible pairs `i < j` within `reach` face diameters, where `f`
/// holds centroid form factors (visibility: `F_ij > 0`) and `corners(i)` face `i`'s corners;
/// pairs the contour form cannot take keep `F` (no entry), as in
/// [`super::near_field::form_factors_exact_near`].
pub fn near_corrections(
    corners: &(dyn Fn(usize) -> [DVec3; 3] + Sync),
    g: &FaceGeometry,
    f: &FormFactors,
    reach: f64,
) -> Vec<(u32, f32)> {
    let n = f.n;
    let rows: Vec<Vec<(u32, f32)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let ci = corners(i);
            (i + 1..n)
                .filter(|&j| f.get(i, j) > 0.0 && is_near(g, i, j, reach))
                .filter_map(|j| {
                    let exact = exact_form_factor(&ci, &corners(j))?;
                    Some(((n * i + j) as u32, (exact - f.get(i, j)) as f32))
                })
                .collect()
        })
        .collect();
    rows.concat()
}

/// Adds `correction` to `f` (both `F_ij` and, by reciprocity, `F_ji`).
pub fn apply(f: &mut FormFactors, correction: &[(u32, f32)], areas: &[f64]) {
    let n = f.n;
    for &(k, delta) in correction {
        let (i, j, delta) = (k as usize / n, k as usize % n, f64::from(delta));
        f.values[n * i + j] += delta;
        f.values[n * j + i] += delta * areas[i] / areas[j];
    }
}
