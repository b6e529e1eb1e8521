//! Functions as compositions of §4's operations, written as the paper writes them.
//!
//! Eq. 4, `y = (Q₁ ⊗₂ x ⊗₃ x)⁻¹ ⊗₁ (Q₂ ⊗₁ x ⊗₂ x)`, reads:
//!
//! ```
//! use galerkin::reduce::Expr;
//! let x = Expr::input("x");
//! let m = Expr::tensor("Q1").times(2, x.clone()).times(3, x.clone());
//! let v = Expr::tensor("Q2").times(1, x.clone()).times(2, x);
//! let y = m.inverse().times(1, v);
//! assert_eq!(y.to_string(), "(Q1 ⊗2 x ⊗3 x)⁻¹ ⊗1 (Q2 ⊗1 x ⊗2 x)");
//! ```

use std::fmt;

/// A value built from named tensors and inputs by §4's operations.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Expr {
    /// A named tensor of the model (reduced tensors replace it after reduction).
    Tensor(String),
    /// A named input vector.
    Input(String),
    /// `base ⊗_a e_a ⊗_b e_b …` (§4 (i)), the axes numbered as in `base` like the paper's
    /// `Q ⊗₂ x ⊗₃ x`. A vector argument removes its axis; a matrix argument (axes `[k, j]`)
    /// replaces axis `k` of `base` by its axis `j`.
    Contract(Box<Expr>, Vec<(usize, Expr)>),
    /// `M⁻¹` (§4 (ii)). Contracted on one axis with a vector it is evaluated as a solve.
    Inverse(Box<Expr>),
    /// `M^p` of a symmetric positive (semi)definite matrix (§4 (iii): `p = 1/n`; also `-1/2`).
    Power(Box<Expr>, f64),
    /// The sum of values with the same axes and bases.
    Sum(Vec<Expr>),
    /// `a − b`.
    Difference(Box<Expr>, Box<Expr>),
    /// `c · e`.
    Scale(f64, Box<Expr>),
}

impl Expr {
    /// A named tensor.
    pub fn tensor(name: &str) -> Self {
        Expr::Tensor(name.to_string())
    }

    /// A named input.
    pub fn input(name: &str) -> Self {
        Expr::Input(name.to_string())
    }

    /// `self ⊗_axis e`. On a contraction of a tensor, the axis is numbered as in that tensor
    /// (the paper's `Q ⊗₂ x ⊗₃ x`), so repeated `times` build one contraction; on anything
    /// else it starts a new one.
    pub fn times(self, axis: usize, e: Expr) -> Self {
        match self {
            Expr::Contract(base, mut args) => {
                args.push((axis, e));
                Expr::Contract(base, args)
            }
            other => Expr::Contract(Box::new(other), vec![(axis, e)]),
        }
    }

    /// `self ⊗_axis e` as a new contraction of the value `self`, whatever it is (axes numbered
    /// as in that value).
    pub fn then(self, axis: usize, e: Expr) -> Self {
        Expr::Contract(Box::new(self), vec![(axis, e)])
    }

    /// `self⁻¹`.
    pub fn inverse(self) -> Self {
        Expr::Inverse(Box::new(self))
    }

    /// `self^(1/n)`, the PSD n-th root.
    pub fn root(self, n: u32) -> Self {
        Expr::Power(Box::new(self), 1.0 / f64::from(n.max(1)))
    }

    /// `self^(-1/2)`.
    pub fn inverse_sqrt(self) -> Self {
        Expr::Power(Box::new(self), -0.5)
    }

    /// `self + other`.
    pub fn plus(self, other: Expr) -> Self {
        match self {
            Expr::Sum(mut terms) => {
                terms.push(other);
                Expr::Sum(terms)
            }
            e => Expr::Sum(vec![e, other]),
        }
    }

    /// `self − other`.
    pub fn minus(self, other: Expr) -> Self {
        Expr::Difference(Box::new(self), Box::new(other))
    }

    /// `c · self`.
    pub fn scaled(self, c: f64) -> Self {
        Expr::Scale(c, Box::new(self))
    }

    /// Every tensor name used, in order of first use.
    pub fn tensors(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.visit(&mut |e| {
            if let Expr::Tensor(n) = e {
                if !out.contains(n) {
                    out.push(n.clone());
                }
            }
        });
        out
    }

    /// Every input name used, in order of first use.
    pub fn inputs(&self) -> Vec<String> {
        let mut out = Vec::new();
        self.visit(&mut |e| {
            if let Expr::Input(n) = e {
                if !out.contains(n) {
                    out.push(n.clone());
                }
            }
        });
        out
    }

    fn visit(&self, f: &mut impl FnMut(&Expr)) {
        f(self);
        match self {
            Expr::Tensor(_) | Expr::Input(_) => {}
            Expr::Contract(b, args) => {
                b.visit(f);
                for (_, a) in args {
                    a.visit(f);
                }
            }
            Expr::Inverse(e) | Expr::Power(e, _) | Expr::Scale(_, e) => e.visit(f),
            Expr::Sum(t) => t.iter().for_each(|e| e.visit(f)),
            Expr::Difference(a, b) => {
                a.visit(f);
                b.visit(f);
            }
        }
    }

    fn is_atom(&self) -> bool {
        matches!(self, Expr::Tensor(_) | Expr::Input(_) | Expr::Inverse(_) | Expr::Power(..))
    }
}

/// Paper notation: `(Q1 ⊗2 x ⊗3 x)⁻¹ ⊗1 (Q2 ⊗1 x ⊗2 x)`.
impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let wrap = |e: &Expr, f: &mut fmt::Formatter<'_>| {
            if e.is_atom() {
                write!(f, "{e}")
            } else {
                write!(f, "({e})")
            }
        };
        match self {
            Expr::Tensor(n) | Expr::Input(n) => write!(f, "{n}"),
            Expr::Contract(b, args) => {
                wrap(b, f)?;
                for (axis, a) in args {
                    write!(f, " ⊗{axis} ")?;
                    wrap(a, f)?;
                }
                Ok(())
            }
            Expr::Inverse(e) => {
                wrap_always(e, f)?;
                write!(f, "⁻¹")
            }
            Expr::Power(e, p) => {
                wrap_always(e, f)?;
                if (1.0 / p).fract() == 0.0 && *p > 0.0 {
                    write!(f, "^(1/{})", (1.0 / p) as i64)
                } else {
                    write!(f, "^({p})")
                }
            }
            Expr::Sum(t) => {
                for (i, e) in t.iter().enumerate() {
                    if i > 0 {
                        write!(f, " + ")?;
                    }
                    wrap(e, f)?;
                }
                Ok(())
            }
            Expr::Difference(a, b) => {
                wrap(a, f)?;
                write!(f, " − ")?;
                wrap(b, f)
            }
            Expr::Scale(c, e) => {
                write!(f, "{c}·")?;
                wrap(e, f)
            }
        }
    }
}

fn wrap_always(e: &Expr, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if matches!(e, Expr::Tensor(_) | Expr::Input(_)) {
        write!(f, "{e}")
    } else {
        write!(f, "({e})")
    }
}
