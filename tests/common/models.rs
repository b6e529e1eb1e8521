//! Reduced models compared with each other: what the precompute over ranks must reproduce.

use galerkin::reduce::ReducedModel;
use galerkin::tensor::Tensor;

/// Columns of `b` equal those of `reference` up to sign, to `tol`.
pub fn same_columns_up_to_sign(b: &Tensor, reference: &Tensor, tol: f64) -> f64 {
    assert_eq!(b.shape(), reference.shape());
    let (n, m) = (b.shape()[0], b.shape()[1]);
    let mut worst = 0.0f64;
    for c in 0..m {
        let dot: f64 = (0..n).map(|i| b.data()[i * m + c] * reference.data()[i * m + c]).sum();
        let sign = dot.signum();
        let d = (0..n)
            .map(|i| (b.data()[i * m + c] - sign * reference.data()[i * m + c]).abs())
            .fold(0.0, f64::max);
        worst = worst.max(d);
    }
    assert!(worst <= tol, "columns differ by {worst:e} > {tol:e}");
    worst
}

/// The largest difference of `a` and `b`, relative to `b`'s largest entry.
pub fn max_relative(a: &Tensor, b: &Tensor) -> f64 {
    assert_eq!(a.shape(), b.shape());
    let scale = b.data().iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    a.data().iter().zip(b.data()).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// Every reduced tensor of `a` against `b`'s, up to the sign of each kept basis's columns
/// (PCA's sign is the eigensolver's choice; the bases the model does not keep must agree in
/// sign): the worst relative difference.
pub fn compare_models(a: &ReducedModel, b: &ReducedModel) -> f64 {
    // The sign of each column of each kept basis, from the bases themselves.
    let mut signs = std::collections::BTreeMap::new();
    let mut names: Vec<&str> = a.tensors().flat_map(|(_, axes, _)| axes.iter().map(String::as_str)).collect();
    names.sort_unstable();
    names.dedup();
    for name in names {
        let Some(ba) = a.basis(name) else { continue };
        let bb = b.basis(name).unwrap_or_else(|| panic!("basis {name}"));
        assert_eq!(ba.matrix().shape(), bb.matrix().shape(), "basis {name}");
        let (n, m) = (ba.full_dim(), ba.reduced_dim());
        let s: Vec<f64> = (0..m)
            .map(|c| {
                (0..n)
                    .map(|i| ba.matrix().data()[i * m + c] * bb.matrix().data()[i * m + c])
                    .sum::<f64>()
                    .signum()
            })
            .collect();
        same_columns_up_to_sign(ba.matrix(), bb.matrix(), 1e-9);
        signs.insert(name.to_string(), s);
    }
    let mut worst = 0.0f64;
    for (name, axes, ta) in a.tensors() {
        let tb = b.tensor(name).unwrap_or_else(|| panic!("tensor {name}"));
        let shape = ta.shape().to_vec();
        let mut flipped = tb.clone();
        for (flat, v) in flipped.data_mut().iter_mut().enumerate() {
            let mut rest = flat;
            for (axis, len) in shape.iter().enumerate().rev() {
                let i = rest % len;
                rest /= len;
                if let Some(s) = signs.get(&axes[axis]) {
                    *v *= s[i];
                }
            }
        }
        worst = worst.max(max_relative(ta, &flipped));
    }
    worst
}
