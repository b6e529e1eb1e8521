//! Seed 000 §4 reproduced: the rational function of Eq. 3 as Eq. 4's composition, §4.2's
//! optimality statements, §4's same-basis rule, and premultiplication against a plain dense
//! f64 reference. All CPU, all f64.

mod common;

use std::collections::BTreeMap;

use galerkin::reduce::{
    premultiply_sparse_with, Bases, Basis, Expr, Model, PremultiplyOptions, ReduceError, Unit,
};
use galerkin::tensor::{matmul, spd_power, symmetric_eigen, transpose, SparseTensor, Tensor};

/// A random `n × m` orthonormal basis.
fn random_basis(n: usize, m: usize, seed: u64) -> Basis {
    let g = Tensor::from_vec(&[n, m], common::random_f32(n * m, seed).into_iter().map(f64::from).collect())
        .unwrap();
    let b = Basis::orthonormalize("random", &g).unwrap();
    assert_eq!(b.reduced_dim(), m);
    b
}

fn random_vec(n: usize, seed: u64) -> Vec<f64> {
    common::random_f32(n, seed).into_iter().map(f64::from).collect()
}

fn inputs<'a>(pairs: &[(&'a str, &'a [f64])]) -> BTreeMap<&'a str, &'a [f64]> {
    pairs.iter().copied().collect()
}

/// Eq. 4's composition `(Q1 ⊗₂ x ⊗₃ x)⁻¹ ⊗₁ (Q2 ⊗₁ x ⊗₂ x)` over the given tensors.
fn eq4_form(q1: SparseTensor, q2: SparseTensor) -> Model {
    let x = Expr::input("x");
    let m = Expr::tensor("Q1").times(2, x.clone()).times(3, x.clone());
    let v = Expr::tensor("Q2").times(1, x.clone()).times(2, x);
    Model::new(m.inverse().times(1, v))
        .with_tensor("Q1", &["y", "y", "x", "x"], q1)
        .with_tensor("Q2", &["y", "x", "x"], q2)
        .with_input("x", "x")
}

/// Eq. 4's tensors for Eq. 3: `Q1 ⊗₂ x ⊗₃ x = diag(x₁², x₂²)`, `Q2 ⊗₁ x ⊗₂ x = [x₁x₂ + x₂², x₁²]`.
fn eq4_model() -> Model {
    let mut q1 = SparseTensor::new(&[2, 2, 2, 2]);
    q1.push(&[0, 0, 0, 0], 1.0); // x₁² in M[0][0]
    q1.push(&[1, 1, 1, 1], 1.0); // x₂² in M[1][1]
    let mut q2 = SparseTensor::new(&[2, 2, 2]);
    q2.push(&[0, 0, 1], 1.0); // x₁x₂ in v[0]
    q2.push(&[0, 1, 1], 1.0); // x₂² in v[0]
    q2.push(&[1, 0, 0], 1.0); // x₁² in v[1]
    eq4_form(q1, q2)
}

#[test]
fn eq3_evaluates_as_eq4_and_reduces_exactly_with_spanning_bases() {
    let model = eq4_model();
    assert_eq!(model.output().to_string(), "(Q1 ⊗2 x ⊗3 x)⁻¹ ⊗1 (Q2 ⊗1 x ⊗2 x)");
    assert_eq!(model.check().unwrap(), ["y"]);
    let mut bases = Bases::new();
    bases.insert("x".into(), random_basis(2, 2, 5));
    bases.insert("y".into(), random_basis(2, 2, 6));
    let reduced = model.reduce(&bases).unwrap();
    for x in [[1.0, 2.0], [-0.5, 0.75], [3.0, -1.25]] {
        let (x1, x2) = (x[0], x[1]);
        let closed_form = [(x1 * x2 + x2 * x2) / (x1 * x1), (x1 * x1) / (x2 * x2)];
        let full = model.evaluate(&inputs(&[("x", &x)])).unwrap();
        for (a, b) in full.data().iter().zip(closed_form) {
            assert!((a - b).abs() <= 1e-14 * b.abs().max(1.0), "full {a} vs closed form {b}");
        }
        let xhat = reduced.project_input("x", &x).unwrap();
        let yhat = reduced.evaluate(&inputs(&[("x", &xhat)])).unwrap();
        let lifted = reduced.lift(yhat.data()).unwrap();
        for (a, b) in lifted.iter().zip(closed_form) {
            // Bases that span the space lose nothing: f64 rounding only.
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "reduced {a} vs full {b}");
        }
    }
}

/// Eq. 4's form in n dimensions: `y = M(x)⁻¹ v(x)` with `M(x) = Q1 ⊗₂ x ⊗₃ x` symmetric
/// positive definite for every x (a |x|²·I term plus small symmetric couplings) and a random
/// quadratic `v(x) = Q2 ⊗₁ x ⊗₂ x`.
fn rational_model(n: usize) -> Model {
    let mut q1 = SparseTensor::new(&[n, n, n, n]);
    let c = random_vec(n * n, 41);
    for i in 0..n {
        for k in 0..n {
            q1.push(&[i, i, k, k], 2.0); // 2|x|² on the diagonal
        }
        for j in 0..n {
            let w = 0.3 * (c[i * n + j] + c[j * n + i]) / n as f64;
            q1.push(&[i, j, i, j], w); // symmetric coupling, small against the diagonal
        }
    }
    let mut q2 = SparseTensor::new(&[n, n, n]);
    let r = random_vec(n * n * n, 42);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                q2.push(&[i, j, k], r[(i * n + j) * n + k]);
            }
        }
    }
    eq4_form(q1, q2)
}

#[test]
fn the_reduction_error_falls_as_the_bases_grow() {
    let n = 16;
    let model = rational_model(n);
    // Inputs living mostly in a few directions of one random basis; the output basis is the
    // same rotation, truncated alike.
    let full_basis = random_basis(n, n, 7);
    let weights: Vec<f64> = (0..n).map(|i| 0.6f64.powi(i as i32)).collect();
    let x = full_basis.lift(&weights);
    let y = model.evaluate(&inputs(&[("x", &x)])).unwrap();
    let mut errors = Vec::new();
    for m in [2, 4, 8, 12, 16] {
        let cols: Vec<f64> = (0..n)
            .flat_map(|i| (0..m).map(move |j| (i, j)))
            .map(|(i, j)| full_basis.matrix().get(&[i, j]))
            .collect();
        let b = Basis::new("truncated", Tensor::from_vec(&[n, m], cols).unwrap(), 1e-12).unwrap();
        let mut bases = Bases::new();
        bases.insert("x".into(), b.clone());
        bases.insert("y".into(), b);
        let reduced = model.reduce(&bases).unwrap();
        let xhat = reduced.project_input("x", &x).unwrap();
        let yhat = reduced.evaluate(&inputs(&[("x", &xhat)])).unwrap();
        let lifted = reduced.lift(yhat.data()).unwrap();
        let err = lifted.iter().zip(y.data()).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt() / y.max_abs();
        errors.push(err);
    }
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "error must fall as the bases grow: {errors:?}");
    }
    assert!(errors[errors.len() - 1] < 1e-11, "spanning bases are exact: {errors:?}");
    assert!(errors[0] > 1e-3, "a 2-dimensional basis cannot be exact: {errors:?}");
}

#[test]
fn the_reduced_contraction_is_the_projection_of_the_full_result() {
    // §4.2 (i): for x in span(B_x), ŷ = B_yᵀ (Q ⊗₁ x ⊗₂ x) exactly.
    let (n, p) = (9, 7);
    let mut q = SparseTensor::new(&[p, n, n]);
    let r = random_vec(p * n * n, 3);
    for (e, v) in r.iter().enumerate() {
        if e % 3 != 0 {
            q.push(&[e / (n * n), (e / n) % n, e % n], *v);
        }
    }
    let x = Expr::input("x");
    let model = Model::new(Expr::tensor("Q").times(1, x.clone()).times(2, x))
        .with_tensor("Q", &["y", "x", "x"], q)
        .with_input("x", "x");
    let mut bases = Bases::new();
    bases.insert("x".into(), random_basis(n, 4, 11));
    bases.insert("y".into(), random_basis(p, 3, 12));
    let reduced = model.reduce(&bases).unwrap();
    let xhat = random_vec(4, 13);
    let x_full = bases["x"].lift(&xhat);
    let y_full = model.evaluate(&inputs(&[("x", &x_full)])).unwrap();
    let projected = bases["y"].project(y_full.data());
    let yhat = reduced.evaluate(&inputs(&[("x", &xhat)])).unwrap();
    for (a, b) in yhat.data().iter().zip(&projected) {
        assert!((a - b).abs() < 1e-13, "{a} vs {b}");
    }
}

fn spd_matrix(n: usize, seed: u64) -> Tensor {
    let m = Tensor::from_vec(&[n, n], random_vec(n * n, seed)).unwrap();
    let mut a = matmul(&transpose(&m), &m).unwrap();
    for i in 0..n {
        let v = a.get(&[i, i]) + 0.5;
        a.set(&[i, i], v);
    }
    a
}

#[test]
fn the_reduced_inverse_is_the_inverse_of_the_reduced_matrix() {
    // §4.2 (ii): ŷ = (BᵀQB)⁻¹ v̂, which is not the Galerkin projection BᵀQ⁻¹B v̂.
    let n = 10;
    let q = spd_matrix(n, 21);
    let model = Model::new(Expr::tensor("Q").inverse().times(1, Expr::input("v")))
        .with_tensor("Q", &["b", "b"], q.clone())
        .with_input("v", "b");
    let mut bases = Bases::new();
    bases.insert("b".into(), random_basis(n, 4, 22));
    let reduced = model.reduce(&bases).unwrap();
    let vhat = random_vec(4, 23);
    let yhat = reduced.evaluate(&inputs(&[("v", &vhat)])).unwrap();
    let b = bases["b"].matrix();
    let btqb = matmul(&matmul(&transpose(b), &q).unwrap(), b).unwrap();
    // (BᵀQB) ŷ must give back v̂.
    let back = btqb.contract(1, yhat.data()).unwrap();
    for (a, v) in back.data().iter().zip(&vhat) {
        assert!((a - v).abs() < 1e-12, "{a} vs {v}");
    }
    // Bᵀ Q⁻¹ B v̂ is a different (suboptimal) answer.
    let qinv = spd_power("Q", &q, -1.0).unwrap();
    let galerkin_of_inverse =
        matmul(&matmul(&transpose(b), &qinv).unwrap(), b).unwrap().contract(1, &vhat).unwrap();
    assert!(galerkin_of_inverse.max_abs_diff(&yhat) > 1e-3, "the two reductions should differ");
}

#[test]
fn the_reduced_root_is_spd_and_its_power_is_the_reduced_matrix() {
    // §4.2 (iii): (BᵀQB)^(1/3) is symmetric positive semidefinite and its cube is BᵀQB.
    let n = 10;
    let q = spd_matrix(n, 31);
    let model = Model::new(Expr::tensor("Q").root(3)).with_tensor("Q", &["b", "b"], q.clone());
    let mut bases = Bases::new();
    bases.insert("b".into(), random_basis(n, 5, 32));
    let r = model.reduce(&bases).unwrap().evaluate(&BTreeMap::new()).unwrap();
    assert!(r.max_abs_diff(&transpose(&r)) < 1e-13, "symmetric");
    let (values, _) = symmetric_eigen("root", &r).unwrap();
    assert!(values.iter().all(|&l| l > 0.0), "positive: {values:?}");
    let b = bases["b"].matrix();
    let btqb = matmul(&matmul(&transpose(b), &q).unwrap(), b).unwrap();
    let cube = matmul(&matmul(&r, &r).unwrap(), &r).unwrap();
    assert!(cube.max_abs_diff(&btqb) < 1e-11 * btqb.max_abs());
    // The Galerkin projection of the full root is a different matrix.
    let full_root = spd_power("Q", &q, 1.0 / 3.0).unwrap();
    let projected_root = matmul(&matmul(&transpose(b), &full_root).unwrap(), b).unwrap();
    assert!(projected_root.max_abs_diff(&r) > 1e-4);
}

#[test]
fn an_inverse_with_different_bases_on_its_axes_is_refused_by_name() {
    let n = 4;
    let model = Model::new(Expr::tensor("K").inverse().times(1, Expr::input("v")))
        .with_tensor("K", &["p", "u"], spd_matrix(n, 1))
        .with_input("v", "u");
    let err = model.check().unwrap_err();
    assert!(matches!(err, ReduceError::SameBasisRequired { op: "inverse", .. }), "{err}");
    let text = err.to_string();
    assert!(
        text.contains('K') && text.contains("`p`") && text.contains("`u`") && text.contains("§4"),
        "{text}"
    );
    let model = Model::new(Expr::tensor("K").root(2)).with_tensor("K", &["p", "u"], spd_matrix(n, 1));
    assert!(matches!(model.check(), Err(ReduceError::SameBasisRequired { op: "root", .. })));
}

#[test]
fn contracting_across_bases_is_refused_by_name() {
    let mut q = SparseTensor::new(&[3, 3]);
    q.push(&[0, 0], 1.0);
    let model = Model::new(Expr::tensor("Q").times(1, Expr::input("x")))
        .with_tensor("Q", &["y", "z"], q)
        .with_input("x", "x");
    let err = model.check().unwrap_err().to_string();
    assert!(
        err.contains("Q ⊗1 x") && err.contains("axis 1") && err.contains("`z`") && err.contains("`x`"),
        "{err}"
    );
    let model = eq4_model();
    let mut bases = Bases::new();
    bases.insert("x".into(), random_basis(2, 2, 1));
    let err = model.reduce(&bases).unwrap_err().to_string();
    assert!(err.contains("no basis `y`") && err.contains("tensor `Q1` axis 0"), "{err}");
}

#[test]
fn composition_through_an_intermediate_basis_trades_accuracy_for_size() {
    // §4.2: q(x) = q1(q2(x)) with q1, q2 quadratic. Reduced as one quartic tensor Q it is
    // optimal; reduced as a composition through B_z it equals B_yᵀ q1(B_z B_zᵀ q2(B_x x̂)).
    let (n, nz) = (6, 5);
    let r1 = random_vec(n * nz * nz, 51);
    let r2 = random_vec(nz * n * n, 52);
    let q1 = Tensor::from_vec(&[n, nz, nz], r1).unwrap();
    let q2 = Tensor::from_vec(&[nz, n, n], r2).unwrap();
    // The single quartic tensor: Q[i,a,b,c,d] = Σ_jk q1[i,j,k] q2[j,a,b] q2[k,c,d].
    let mut q = Tensor::zeros(&[n, n, n, n, n]);
    for i in 0..n {
        for (a, b, c, d) in
            (0..n * n * n * n).map(|t| (t / (n * n * n), (t / (n * n)) % n, (t / n) % n, t % n))
        {
            let mut s = 0.0;
            for j in 0..nz {
                for k in 0..nz {
                    s += q1.get(&[i, j, k]) * q2.get(&[j, a, b]) * q2.get(&[k, c, d]);
                }
            }
            q.set(&[i, a, b, c, d], s);
        }
    }
    let x = Expr::input("x");
    let inner = Expr::tensor("Q2").times(1, x.clone()).times(2, x.clone());
    let composed = Model::new(Expr::tensor("Q1").times(1, inner.clone()).times(2, inner))
        .with_tensor("Q1", &["y", "z", "z"], q1.clone())
        .with_tensor("Q2", &["z", "x", "x"], q2.clone())
        .with_input("x", "x");
    let single = Model::new(
        Expr::tensor("Q").times(1, x.clone()).times(2, x.clone()).times(3, x.clone()).times(4, x.clone()),
    )
    .with_tensor("Q", &["y", "x", "x", "x", "x"], q)
    .with_input("x", "x");
    let xs = random_vec(n, 53);
    let full_c = composed.evaluate(&inputs(&[("x", &xs)])).unwrap();
    let full_s = single.evaluate(&inputs(&[("x", &xs)])).unwrap();
    assert!(full_c.max_abs_diff(&full_s) < 1e-12 * full_s.max_abs(), "identical in the full space");

    let mut bases = Bases::new();
    bases.insert("x".into(), random_basis(n, 3, 54));
    bases.insert("y".into(), random_basis(n, 3, 55));
    bases.insert("z".into(), random_basis(nz, 2, 56));
    let xhat = random_vec(3, 57);
    let red_c = composed.reduce(&bases).unwrap().evaluate(&inputs(&[("x", &xhat)])).unwrap();
    let red_s = single.reduce(&bases).unwrap().evaluate(&inputs(&[("x", &xhat)])).unwrap();
    // The composition equals B_yᵀ q1(B_z B_zᵀ q2(B_x x̂)).
    let z_full = q2.contract_axes(&[(1, &bases["x"].lift(&xhat)), (2, &bases["x"].lift(&xhat))]).unwrap();
    let z_proj = bases["z"].lift(&bases["z"].project(z_full.data()));
    let y_full = q1.contract_axes(&[(1, &z_proj), (2, &z_proj)]).unwrap();
    let want = bases["y"].project(y_full.data());
    for (a, b) in red_c.data().iter().zip(&want) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
    // The single tensor is the optimal reduction: the projection of the true result.
    let truth =
        bases["y"].project(single.evaluate(&inputs(&[("x", &bases["x"].lift(&xhat))])).unwrap().data());
    let err = |v: &[f64]| v.iter().zip(&truth).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    assert!(err(red_s.data()) < 1e-12);
    assert!(err(red_c.data()) > 1e-6, "the extra projection B_z B_zᵀ costs accuracy");
    // …and the composition's reduced tensors are smaller: 3·2² + 2·3² = 30 vs 3⁵ = 243.
    let c = composed.reduce(&bases).unwrap();
    let s = single.reduce(&bases).unwrap();
    assert_eq!(c.tensor("Q1").unwrap().len() + c.tensor("Q2").unwrap().len(), 30);
    assert_eq!(s.tensor("Q").unwrap().len(), 243);
}

#[test]
fn sparse_premultiplication_matches_the_dense_reference_for_orders_2_to_5() {
    for order in 2..=5usize {
        let q = common::random_sparse(order, 400);
        let shape = q.shape().to_vec();
        let reduced: Vec<usize> = (0..order).map(|a| 2 + a % 3).collect();
        let bases: Vec<Basis> =
            (0..order).map(|a| random_basis(shape[a], reduced[a], 100 + a as u64)).collect();
        let mats: Vec<&Tensor> = bases.iter().map(Basis::matrix).collect();
        let (got, plan) = premultiply_sparse_with(&q, &mats, PremultiplyOptions::default()).unwrap();
        let want = common::dense_reference(&q.to_dense(), &mats);
        assert_eq!(got.shape(), reduced.as_slice());
        // f64 sums of a few hundred terms of size ≤ 1: rounding ~1e-15 per term.
        assert!(got.max_abs_diff(&want) < 1e-12 * want.max_abs().max(1.0), "order {order}");
        let mut sorted: Vec<usize> = plan
            .stages
            .iter()
            .flatten()
            .map(|u| match u {
                Unit::Axis(a) => *a,
                Unit::Group(_) => unreachable!("no symmetric groups here"),
            })
            .collect();
        sorted.sort();
        assert_eq!(sorted, (0..order).collect::<Vec<_>>(), "each axis once");
        assert_eq!(*plan.entries.last().unwrap(), 1, "the last stage leaves one dense block");
    }
}

#[test]
fn symmetric_axes_are_contracted_packed_and_match_the_dense_reference() {
    // A V-like tensor: result and velocity axes, three symmetric geometry axes in one basis.
    let (np, ng) = (12, 9);
    let mut q = SparseTensor::new(&[np, np, ng, ng, ng]).with_symmetric_axes(&[2, 3, 4]).unwrap();
    let r = random_vec(600, 77);
    for (e, &v) in r.iter().enumerate() {
        let cell = e % 4;
        let p = 3 * cell + e % 3;
        // Geometry indices from the cell's own few coordinates (locality), any order.
        let g = |k: usize| (2 * cell + (e / (3 + k)) % 3) % ng;
        q.push(&[p, p, g(0), g(1), g(2)], v);
    }
    let bp = random_basis(np, 5, 78);
    let bg = random_basis(ng, 4, 79);
    let mats = [bp.matrix(), bp.matrix(), bg.matrix(), bg.matrix(), bg.matrix()];
    let (got, plan) = premultiply_sparse_with(&q, &mats, PremultiplyOptions::default()).unwrap();
    let want = common::dense_reference(&q.to_dense(), &mats);
    assert!(got.max_abs_diff(&want) < 1e-12 * want.max_abs(), "diff {}", got.max_abs_diff(&want));
    assert!(plan.stages.iter().flatten().any(|u| *u == Unit::Group(vec![2, 3, 4])), "{plan:?}");
    // The result is symmetric in its last three axes.
    assert_eq!(got.get(&[1, 2, 0, 1, 3]), got.get(&[1, 2, 3, 0, 1]));
    // Progress is reported against the plan's total.
    let last = std::sync::Mutex::new((0.0, 0.0));
    let report = |done: f64, total: f64| *last.lock().unwrap() = (done, total);
    let options = PremultiplyOptions { progress: Some(&report), ..PremultiplyOptions::default() };
    premultiply_sparse_with(&q, &mats, options).unwrap();
    let (done, total) = *last.lock().unwrap();
    assert!(total > 0.0 && (done - total).abs() < 1e-6 * total, "{done} of {total}");
}

/// Table 2's `P[k, k, i]` (pairs `k = n·i + j`): its two pair axes contracted first cost
/// `n²·m·(1 + m)`, its face axis first `n²·m²·m_a` and more — the plan takes the cheap order, and
/// the streamed finishing stage it chooses gives the dense reference's result.
#[test]
fn the_plan_contracts_units_in_their_cheapest_order() {
    let n = 12;
    let mut q = SparseTensor::new(&[n * n, n * n, n]);
    for i in 0..n {
        for j in 0..n {
            q.push(&[n * i + j, n * i + j, i], 1.0 + (i * n + j) as f64 / 100.0);
        }
    }
    let (m, ma) = (6, 3);
    let (bp, ba) = (random_basis(n * n, m, 201), random_basis(n, ma, 202));
    let mats = [bp.matrix(), bp.matrix(), ba.matrix()];
    let (got, plan) = premultiply_sparse_with(&q, &mats, PremultiplyOptions::default()).unwrap();
    let want = common::dense_reference(&q.to_dense(), &mats);
    assert!(got.max_abs_diff(&want) < 1e-12 * want.max_abs(), "diff {}", got.max_abs_diff(&want));
    let cheapest = ((n * n) * m * (1 + m) + n * m * m * ma) as f64;
    assert!((plan.total_flops() - cheapest).abs() < 1e-9 * cheapest, "{plan:?}, cheapest {cheapest}");
    assert_eq!(plan.stages.len(), 1, "one streamed finishing stage: {plan:?}");
    assert_eq!(plan.stages[0][0], Unit::Axis(2), "the face axis contracted last: {plan:?}");
}
