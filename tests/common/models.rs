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

/// The fluid's constraint basis `B_d`: an SVD of `D [B_f B_h]` cut at singular values of 1e-9,
/// which magnifies the rounding of its input by up to the inverse of its singular-value gaps —
/// so it and the tensors it reduces agree between rank counts to about 1e-8 on small cases and
/// 2e-7 on the cavity (BENCHMARKS.md), not to rounding.
pub const CONSTRAINT_BASES: [&str; 1] = ["d"];

/// How closely two models agree.
#[derive(Debug)]
pub struct Agreement {
    /// The worst relative difference of the tensors that carry no constraint basis.
    pub worst: f64,
    /// The worst of the tensors that carry one ([`CONSTRAINT_BASES`]); 0 if none does.
    pub constraint: f64,
}

/// Every reduced tensor of `a` against `b`'s, up to the sign of each kept basis's columns
/// (PCA's sign is the eigensolver's choice; the bases the model does not keep must agree in
/// sign): the worst relative differences. Kept bases must agree column by column to 1e-9
/// (constraint bases to 1e-6).
pub fn compare_models(a: &ReducedModel, b: &ReducedModel) -> Agreement {
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
        let tol = if CONSTRAINT_BASES.contains(&name) { 1e-6 } else { 1e-9 };
        same_columns_up_to_sign(ba.matrix(), bb.matrix(), tol);
        signs.insert(name.to_string(), s);
    }
    let mut agreement = Agreement { worst: 0.0, constraint: 0.0 };
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
        let d = max_relative(ta, &flipped);
        if axes.iter().any(|x| CONSTRAINT_BASES.contains(&x.as_str())) {
            agreement.constraint = agreement.constraint.max(d);
        } else {
            agreement.worst = agreement.worst.max(d);
        }
    }
    agreement
}
