//! One-dimensional bases of the tensor-product spectral element (seed 002, "Calculating
//! Lagrange Polynomial Coefficients"): Lagrange polynomials through Gauss–Lobatto–Legendre,
//! equispaced or Gauss–Legendre nodes, and the Bernstein polynomials, all on the reference
//! interval [0, 1] (the convention of VTK's Lagrange cells and of MFEM).
//!
//! The Lagrange basis is evaluated in the first ("modified Lagrange") barycentric form,
//! ℓ_j(x) = w_j ∏_{k≠j} (x − x_k) with barycentric weights w_j = 1 / ∏_{k≠j} (x_j − x_k)
//! (Berrut & Trefethen 2004, Eq. 3.3), which Higham (2004) proved backward stable at any order.
//! The products ∏_{k<j} and ∏_{k>j} are formed as prefix and suffix products, so all n + 1
//! values and their derivatives cost O(n), need no division, and are exact at the nodes. The
//! Bernstein basis is evaluated by the de Casteljau triangle. `shaders-glsl/include/lagrange.glsl`
//! is the GLSL twin; `tests/spectral.rs` checks that the two agree.

use super::error::SpectralError;

/// The highest order a basis supports: the GLSL twin keeps `MAX_ORDER + 1` values per axis in
/// fixed-size arrays.
pub const MAX_ORDER: usize = 12;

/// Where an element's degrees of freedom sit along each axis (seed 002, Fig. 3 and
/// "Quadrature Points").
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum NodeSet {
    /// Gauss–Lobatto–Legendre points: the endpoints and the roots of P′_n (spectral elements).
    GaussLobatto,
    /// Equally spaced points, endpoints included (VTK's Lagrange cells, MFEM's "closed
    /// uniform" bases).
    Equispaced,
    /// Gauss–Legendre points: the roots of P_{n+1}, no endpoints (MFEM's L2 default).
    Gauss,
    /// Not nodes but Bernstein coefficients: the value is Σ c_i B_i^n(x) (MFEM's "positive"
    /// bases).
    Bernstein,
}

impl NodeSet {
    /// Every node set, in the command line's order.
    pub const ALL: [NodeSet; 4] = [Self::GaussLobatto, Self::Equispaced, Self::Gauss, Self::Bernstein];

    /// The name used on the command line and in errors.
    pub fn name(self) -> &'static str {
        match self {
            Self::GaussLobatto => "gll",
            Self::Equispaced => "equispaced",
            Self::Gauss => "gauss",
            Self::Bernstein => "bernstein",
        }
    }

    /// Parses [`NodeSet::name`].
    pub fn by_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Whether the element's corner values are degrees of freedom (so that a boundary node
    /// lies on the boundary): true except for Gauss–Legendre.
    pub fn has_endpoints(self) -> bool {
        self != Self::Gauss
    }
}

/// A one-dimensional basis of order `n` (n + 1 functions) on [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct Basis1d {
    /// Node set (or Bernstein).
    pub set: NodeSet,
    /// Polynomial order n.
    pub order: usize,
    /// The n + 1 nodes in increasing order (for Bernstein: the Greville abscissae i / n, where
    /// the coefficient c_i "sits").
    pub nodes: Vec<f64>,
    /// Barycentric weights w_j = 1 / ∏_{k≠j} (x_j − x_k) (unused for Bernstein).
    pub weights: Vec<f64>,
}

impl Basis1d {
    /// The basis of `order` on `set`; orders 1..=[`MAX_ORDER`].
    pub fn new(set: NodeSet, order: usize) -> Result<Self, SpectralError> {
        if !(1..=MAX_ORDER).contains(&order) {
            return Err(SpectralError::Order {
                what: format!("{} basis", set.name()),
                order,
                max: MAX_ORDER,
            });
        }
        let nodes = match set {
            NodeSet::GaussLobatto => gauss_lobatto_nodes(order),
            NodeSet::Equispaced | NodeSet::Bernstein => {
                (0..=order).map(|i| i as f64 / order as f64).collect()
            }
            NodeSet::Gauss => gauss_nodes(order + 1),
        };
        let weights = barycentric_weights(&nodes);
        Ok(Self { set, order, nodes, weights })
    }

    /// Number of functions, n + 1.
    pub fn len(&self) -> usize {
        self.order + 1
    }

    /// Always false: a basis has at least two functions.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The n + 1 basis values at `x` into `values` and, if given, their derivatives into
    /// `derivatives`. Lagrange: first barycentric form by prefix and suffix products; Bernstein:
    /// the de Casteljau triangle, with B_i^n′ = n (B_{i−1}^{n−1} − B_i^{n−1}).
    pub fn eval(&self, x: f64, values: &mut [f64], derivatives: Option<&mut [f64]>) {
        let m = self.len();
        if self.set == NodeSet::Bernstein {
            bernstein(self.order, x, &mut values[..m], derivatives.map(|d| &mut d[..m]));
            return;
        }
        // prefix[j] = ∏_{k<j} (x − x_k), suffix[j] = ∏_{k≥j} (x − x_k), with derivatives.
        let mut prefix = [0.0; MAX_ORDER + 2];
        let mut dprefix = [0.0; MAX_ORDER + 2];
        let mut suffix = [0.0; MAX_ORDER + 2];
        let mut dsuffix = [0.0; MAX_ORDER + 2];
        prefix[0] = 1.0;
        for k in 0..m {
            let d = x - self.nodes[k];
            dprefix[k + 1] = dprefix[k] * d + prefix[k];
            prefix[k + 1] = prefix[k] * d;
        }
        suffix[m] = 1.0;
        for k in (0..m).rev() {
            let d = x - self.nodes[k];
            dsuffix[k] = dsuffix[k + 1] * d + suffix[k + 1];
            suffix[k] = suffix[k + 1] * d;
        }
        for j in 0..m {
            values[j] = self.weights[j] * prefix[j] * suffix[j + 1];
        }
        if let Some(d) = derivatives {
            for j in 0..m {
                d[j] = self.weights[j] * (dprefix[j] * suffix[j + 1] + prefix[j] * dsuffix[j + 1]);
            }
        }
    }

    /// The n + 1 values at `x` as a vector (convenience for references and tests).
    pub fn values(&self, x: f64) -> Vec<f64> {
        let mut v = vec![0.0; self.len()];
        self.eval(x, &mut v, None);
        v
    }

    /// Coefficients in this basis of the polynomial (degree ≤ n) whose values at `points` are
    /// `values` — interpolation, by a dense solve in f64. For Lagrange bases at their own nodes
    /// this is the identity; it converts, e.g., node values to Bernstein coefficients.
    pub fn interpolate(&self, points: &[f64], values: &[f64]) -> Vec<f64> {
        let m = self.len();
        let mut a = vec![0.0; m * m];
        for (r, &p) in points.iter().enumerate().take(m) {
            self.eval(p, &mut a[r * m..(r + 1) * m], None);
        }
        solve_dense(&mut a, values.to_vec(), m)
    }
}

impl Basis1d {
    /// Tensor-product interpolation: coefficients in this basis^⊗`dim` of the values `v` given
    /// at `points`^`dim` (first axis fastest), by the 1D interpolation along each axis in turn.
    pub fn tensor_interpolate(&self, points: &[f64], v: &[f64], dim: usize) -> Vec<f64> {
        let m = self.len();
        let mut out = v.to_vec();
        for axis in 0..dim {
            let stride = m.pow(axis as u32);
            for flat in 0..out.len() {
                // Each line along `axis` once, from its first entry.
                if !(flat / stride).is_multiple_of(m) {
                    continue;
                }
                let line: Vec<f64> = (0..m).map(|t| out[flat + t * stride]).collect();
                let c = self.interpolate(points, &line);
                for t in 0..m {
                    out[flat + t * stride] = c[t];
                }
            }
        }
        out
    }
}

/// de Casteljau's triangle for the Bernstein basis of degree `n` at `x`.
fn bernstein(n: usize, x: f64, values: &mut [f64], derivatives: Option<&mut [f64]>) {
    values.fill(0.0);
    values[0] = 1.0;
    let step = |b: &mut [f64], r: usize| {
        // Degree r − 1 → r, from the top so that b[i − 1] is still of degree r − 1.
        b[r] = x * b[r - 1];
        for i in (1..r).rev() {
            b[i] = (1.0 - x) * b[i] + x * b[i - 1];
        }
        b[0] *= 1.0 - x;
    };
    for r in 1..n {
        step(values, r);
    }
    if let Some(d) = derivatives {
        for i in 0..=n {
            let left = if i > 0 { values[i - 1] } else { 0.0 };
            let right = if i < n { values[i] } else { 0.0 };
            d[i] = n as f64 * (left - right);
        }
    }
    step(values, n);
}

/// Barycentric weights w_j = 1 / ∏_{k≠j} (x_j − x_k).
pub fn barycentric_weights(nodes: &[f64]) -> Vec<f64> {
    (0..nodes.len())
        .map(|j| 1.0 / (0..nodes.len()).filter(|&k| k != j).map(|k| nodes[j] - nodes[k]).product::<f64>())
        .collect()
}

/// Legendre P_n(x) and P_{n−1}(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    (p1, p0)
}

/// The n + 1 Gauss–Lobatto–Legendre points of order n on [0, 1]: the endpoints and the roots
/// of P′_n, by Newton's method on (x P_n − P_{n−1}) from the Chebyshev–Lobatto points.
pub fn gauss_lobatto_nodes(n: usize) -> Vec<f64> {
    let mut x: Vec<f64> = (0..=n).map(|k| -(std::f64::consts::PI * k as f64 / n as f64).cos()).collect();
    for xk in x.iter_mut().take(n).skip(1) {
        for _ in 0..100 {
            let (pn, pm) = legendre(n, *xk);
            let dx = (*xk * pn - pm) / ((n + 1) as f64 * pn);
            *xk -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
    }
    x.iter().map(|&t| 0.5 * (t + 1.0)).collect()
}

/// The m Gauss–Legendre points (roots of P_m) on [0, 1], increasing, by Newton's method.
pub fn gauss_nodes(m: usize) -> Vec<f64> {
    let mut x: Vec<f64> =
        (0..m).map(|k| -(std::f64::consts::PI * (k as f64 + 0.75) / (m as f64 + 0.5)).cos()).collect();
    for xk in x.iter_mut() {
        for _ in 0..100 {
            let (pm, pm1) = legendre(m, *xk);
            let dp = m as f64 * (*xk * pm - pm1) / (*xk * *xk - 1.0);
            let dx = pm / dp;
            *xk -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
    }
    x.iter().map(|&t| 0.5 * (t + 1.0)).collect()
}

/// The m-point Gauss–Legendre rule on [0, 1]: its nodes ([`gauss_nodes`]) and weights
/// `1 / ((1 − x²) P′_m(x)²)` at the nodes' images `x` in [−1, 1] (summing to 1; exact for
/// polynomials of degree 2m − 1).
pub fn gauss_rule(m: usize) -> (Vec<f64>, Vec<f64>) {
    let nodes = gauss_nodes(m);
    let weights = nodes
        .iter()
        .map(|&t| {
            let x = 2.0 * t - 1.0;
            let (pm, pm1) = legendre(m, x);
            let dp = m as f64 * (x * pm - pm1) / (x * x - 1.0);
            1.0 / ((1.0 - x * x) * dp * dp)
        })
        .collect();
    (nodes, weights)
}

/// Solves the dense m × m system `a` x = b by Gaussian elimination with partial pivoting (f64;
/// the small interpolation systems of a basis).
fn solve_dense(a: &mut [f64], mut b: Vec<f64>, m: usize) -> Vec<f64> {
    for c in 0..m {
        let p = (c..m).max_by(|&i, &j| a[i * m + c].abs().total_cmp(&a[j * m + c].abs())).unwrap_or(c);
        if p != c {
            for k in 0..m {
                a.swap(c * m + k, p * m + k);
            }
            b.swap(c, p);
        }
        for r in c + 1..m {
            let f = a[r * m + c] / a[c * m + c];
            for k in c..m {
                a[r * m + k] -= f * a[c * m + k];
            }
            b[r] -= f * b[c];
        }
    }
    for c in (0..m).rev() {
        let s: f64 = (c + 1..m).map(|k| a[c * m + k] * b[k]).sum();
        b[c] = (b[c] - s) / a[c * m + c];
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The m-point rule integrates monomials up to degree 2m − 1 exactly (∫₀¹ xᵏ = 1/(k+1)).
    #[test]
    fn gauss_rules_integrate_polynomials_of_degree_2m_minus_1() {
        for m in [1, 2, 5, 8, 16] {
            let (x, w) = gauss_rule(m);
            for k in 0..2 * m {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!((q - 1.0 / (k + 1) as f64).abs() < 1e-13, "m {m}, degree {k}: {q}");
            }
        }
    }

    #[test]
    fn lagrange_bases_are_cardinal_and_reproduce_polynomials() {
        for set in [NodeSet::GaussLobatto, NodeSet::Equispaced, NodeSet::Gauss] {
            for n in 1..=MAX_ORDER {
                let b = Basis1d::new(set, n).unwrap();
                for (i, &x) in b.nodes.iter().enumerate() {
                    let v = b.values(x);
                    for (j, &vj) in v.iter().enumerate() {
                        assert!((vj - f64::from(u8::from(i == j))).abs() < 1e-12, "{set:?} n={n}");
                    }
                }
                // x^n is reproduced, and so is its derivative.
                let f: Vec<f64> = b.nodes.iter().map(|&x| x.powi(n as i32)).collect();
                for x in [0.0, 0.13, 0.5, 0.77, 1.0] {
                    let (mut v, mut d) = (vec![0.0; n + 1], vec![0.0; n + 1]);
                    b.eval(x, &mut v, Some(&mut d));
                    let p: f64 = v.iter().zip(&f).map(|(a, b)| a * b).sum();
                    let dp: f64 = d.iter().zip(&f).map(|(a, b)| a * b).sum();
                    assert!((p - x.powi(n as i32)).abs() < 1e-10, "{set:?} n={n} x={x}: {p}");
                    let exact = n as f64 * x.powi(n as i32 - 1);
                    assert!((dp - exact).abs() < 1e-8 * n as f64 * n as f64, "{set:?} n={n} x={x}: {dp}");
                }
            }
        }
    }

    #[test]
    fn node_sets_are_the_textbook_ones() {
        // GLL of order 4 on [-1, 1]: 0, ±sqrt(3/7), ±1.
        let g = gauss_lobatto_nodes(4);
        let s = (3.0f64 / 7.0).sqrt();
        for (a, b) in g.iter().zip([-1.0, -s, 0.0, s, 1.0]) {
            assert!((a - 0.5 * (b + 1.0)).abs() < 1e-15);
        }
        // Gauss with 2 points: ±1/sqrt(3).
        let q = gauss_nodes(2);
        assert!((q[0] - 0.5 * (1.0 - 1.0 / 3f64.sqrt())).abs() < 1e-15);
        assert!(Basis1d::new(NodeSet::Equispaced, 0).is_err());
        assert!(Basis1d::new(NodeSet::Equispaced, MAX_ORDER + 1).is_err());
    }

    #[test]
    fn bernstein_partition_of_unity_and_derivative() {
        for n in 1..=MAX_ORDER {
            let b = Basis1d::new(NodeSet::Bernstein, n).unwrap();
            for x in [0.0, 0.3, 0.5, 1.0] {
                let (mut v, mut d) = (vec![0.0; n + 1], vec![0.0; n + 1]);
                b.eval(x, &mut v, Some(&mut d));
                assert!((v.iter().sum::<f64>() - 1.0).abs() < 1e-14);
                assert!(d.iter().sum::<f64>().abs() < 1e-12);
                // B_i^n(x) = C(n, i) x^i (1 − x)^(n − i).
                for (i, vi) in v.iter().enumerate() {
                    let c = (0..i).fold(1.0, |c, k| c * (n - k) as f64 / (k + 1) as f64);
                    let exact = c * x.powi(i as i32) * (1.0 - x).powi((n - i) as i32);
                    assert!((vi - exact).abs() < 1e-14);
                }
            }
            // Interpolating x^n at the GLL points gives Bernstein coefficients that reproduce it.
            let pts = gauss_lobatto_nodes(n);
            let f: Vec<f64> = pts.iter().map(|x| x.powi(n as i32)).collect();
            let c = b.interpolate(&pts, &f);
            let v = b.values(0.37);
            let p: f64 = v.iter().zip(&c).map(|(a, b)| a * b).sum();
            assert!((p - 0.37f64.powi(n as i32)).abs() < 1e-12);
        }
    }
}
