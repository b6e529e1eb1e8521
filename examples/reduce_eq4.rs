//! Seed 000 §4.1 end to end: the rational function of Eq. 3 written as Eq. 4's composition,
//! reduced with bases for `x` and `y`, evaluated in both spaces, and saved as safetensors.
//!
//! Run: `cargo run --release --example reduce_eq4 [out.safetensors]`, then in Python:
//! `from safetensors.numpy import load_file; load_file("out/eq4.safetensors")`.

use std::collections::BTreeMap;
use std::path::PathBuf;

use galerkin::reduce::{Bases, Basis, Expr, Model};
use galerkin::tensor::{SparseTensor, Tensor};

fn main() -> anyhow::Result<()> {
    // Eq. 4: y = (Q1 ⊗2 x ⊗3 x)⁻¹ ⊗1 (Q2 ⊗1 x ⊗2 x).
    let mut q1 = SparseTensor::new(&[2, 2, 2, 2]);
    q1.push(&[0, 0, 0, 0], 1.0);
    q1.push(&[1, 1, 1, 1], 1.0);
    let mut q2 = SparseTensor::new(&[2, 2, 2]);
    q2.push(&[0, 0, 1], 1.0);
    q2.push(&[0, 1, 1], 1.0);
    q2.push(&[1, 0, 0], 1.0);
    let x = Expr::input("x");
    let m = Expr::tensor("Q1").times(2, x.clone()).times(3, x.clone());
    let v = Expr::tensor("Q2").times(1, x.clone()).times(2, x);
    let model = Model::new(m.inverse().times(1, v))
        .with_tensor("Q1", &["y", "y", "x", "x"], q1)
        .with_tensor("Q2", &["y", "x", "x"], q2)
        .with_input("x", "x");
    println!("f(x) = {}", model.output());

    // Rotations of the plane: bases that span it, so the reduction is exact.
    let rotation = |a: f64| Tensor::matrix(2, 2, vec![a.cos(), -a.sin(), a.sin(), a.cos()]);
    let mut bases = Bases::new();
    bases.insert("x".into(), Basis::new("x", rotation(0.3)?, 1e-12)?);
    bases.insert("y".into(), Basis::new("y", rotation(-1.1)?, 1e-12)?);
    let reduced = model.reduce(&bases)?;

    let xs = [1.0, 2.0];
    let full = model.evaluate(&[("x", &xs[..])].into_iter().collect::<BTreeMap<_, _>>())?;
    let xhat = reduced.project_input("x", &xs)?;
    let yhat = reduced.evaluate(&[("x", &xhat[..])].into_iter().collect::<BTreeMap<_, _>>())?;
    println!(
        "x = {xs:?}: full f(x) = {:?}, reduced and lifted = {:?}",
        full.data(),
        reduced.lift(yhat.data())?
    );
    println!("closed form: [(x1 x2 + x2²)/x1², x1²/x2²] = [{}, {}]", (2.0 + 4.0) / 1.0, 1.0 / 4.0);

    let path =
        std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| PathBuf::from("out/eq4.safetensors"));
    reduced.save(&path)?;
    println!("saved {}", path.display());
    Ok(())
}
