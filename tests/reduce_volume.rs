//! The benchmark's reduced fluid step against closed forms: on a Freudenthal grid of unit
//! cubes every cell has volume 1/6, so `u = V(g)⁻¹ p = 6p` in the full space, and with any
//! orthonormal velocity basis `û = (B_uᵀ V(g) B_u)⁻¹ p̂ = 6 p̂` (the reduced volume matrix is
//! `B_uᵀ (I/6) B_u = I/6` when ĝ lifts to the grid's own coordinates).

mod common;

use std::collections::BTreeMap;

use galerkin::bench::reduce::velocity_from_momentum_model;
use galerkin::reduce::synthetic::{volume_tensor, TetGrid};
use galerkin::reduce::{Bases, Basis};
use galerkin::tensor::Tensor;

#[test]
fn velocity_from_momentum_matches_the_closed_form_in_both_spaces() {
    let grid = TetGrid::with_cells(30);
    let model = velocity_from_momentum_model(volume_tensor(&grid));
    let coords = grid.coordinates();
    let n_u = 3 * grid.cells.len();
    let p: Vec<f64> = common::random_f32(n_u, 5).into_iter().map(f64::from).collect();
    let inputs: BTreeMap<&str, &[f64]> = [("g", &coords[..]), ("p", &p[..])].into_iter().collect();
    let u = model.evaluate(&inputs).unwrap();
    for (ui, pi) in u.data().iter().zip(&p) {
        assert!((ui - 6.0 * pi).abs() < 1e-12, "{ui} vs {}", 6.0 * pi);
    }

    let m = 7;
    let random = |n: usize, k: usize, seed: u64| {
        Tensor::from_vec(&[n, k], common::random_f32(n * k, seed).into_iter().map(f64::from).collect())
            .unwrap()
    };
    let mut gcols = random(coords.len(), 3, 9).into_data();
    for (i, &c) in coords.iter().enumerate() {
        gcols[3 * i] = c; // column 0: the rest pose itself
    }
    let mut bases = Bases::new();
    bases.insert(
        "g".into(),
        Basis::orthonormalize("g", &Tensor::from_vec(&[coords.len(), 3], gcols).unwrap()).unwrap(),
    );
    bases.insert("u".into(), Basis::orthonormalize("u", &random(n_u, m, 10)).unwrap());
    let reduced = model.reduce(&bases).unwrap();
    let ghat = reduced.project_input("g", &coords).unwrap();
    let phat = reduced.project_input("p", &p).unwrap();
    let uhat = reduced.evaluate(&[("g", &ghat[..]), ("p", &phat[..])].into_iter().collect()).unwrap();
    for (a, b) in uhat.data().iter().zip(&phat) {
        // Conditioning of I/6 is 1: f64 rounding of ~10³ terms.
        assert!((a - 6.0 * b).abs() < 1e-11, "{a} vs {}", 6.0 * b);
    }
}
