//! The f64 interpreter of an [`Expression`]: the reference the device's per-pixel evaluation
//! is tested against, and the colour range's sampler.

use super::{BinaryOp, Expression, Function, Node};

/// What an expression reads at one point: every slot's value and physical gradient, and the
/// scope's variables.
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    /// Slot k's value (slot 0: the shown field).
    pub values: &'a [f64],
    /// Slot k's physical gradient.
    pub gradients: &'a [[f64; 3]],
    /// Variable k's value ([`super::Scope::variables`]; a scalar in its first component).
    pub variables: &'a [[f64; 3]],
}

/// The physical (surface) gradient of a field with reference derivatives `d` = (f_ξ, f_η) on a
/// quadrilateral with tangents `t` = (∂x/∂ξ, ∂x/∂η): [t_ξ t_η] G⁻¹ d with the metric
/// G_ij = t_i · t_j — the inverse transpose of the Jacobian on planar elements, the tangential
/// gradient on surfaces. Twin of `spectral_physical_gradient` (spectral_element.glsl).
pub fn physical_gradient(t: [[f64; 3]; 2], d: [f64; 2]) -> [f64; 3] {
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (g11, g12, g22) = (dot(t[0], t[0]), dot(t[0], t[1]), dot(t[1], t[1]));
    let det = g11 * g22 - g12 * g12;
    let c = [(g22 * d[0] - g12 * d[1]) / det, (-g12 * d[0] + g11 * d[1]) / det];
    std::array::from_fn(|i| c[0] * t[0][i] + c[1] * t[1][i])
}

/// A value of the language.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Value {
    Scalar(f64),
    Vector([f64; 3]),
}

impl Value {
    fn scalar(self) -> f64 {
        match self {
            Value::Scalar(s) => s,
            // Type-checked trees never ask; NaN keeps a logic error visible.
            Value::Vector(_) => f64::NAN,
        }
    }
    fn vector(self) -> [f64; 3] {
        match self {
            Value::Vector(v) => v,
            Value::Scalar(_) => [f64::NAN; 3],
        }
    }
}

fn eval(node: &Node, inputs: &Inputs<'_>) -> Value {
    use Value::{Scalar, Vector};
    match node {
        Node::Number(v) => Scalar(*v),
        Node::Variable(k, ty) => {
            let v = inputs.variables.get(*k).copied().unwrap_or([f64::NAN; 3]);
            if *ty == super::Type::Scalar {
                Scalar(v[0])
            } else {
                Vector(v)
            }
        }
        Node::Value(k) => Scalar(inputs.values.get(*k).copied().unwrap_or(f64::NAN)),
        Node::Gradient(k) => Vector(inputs.gradients.get(*k).copied().unwrap_or([f64::NAN; 3])),
        Node::Negate(a) => match eval(a, inputs) {
            Scalar(s) => Scalar(-s),
            Vector(v) => Vector(v.map(|c| -c)),
        },
        Node::Component(a, c) => Scalar(eval(a, inputs).vector()[*c]),
        Node::Binary(op, a, b) => {
            let (a, b) = (eval(a, inputs), eval(b, inputs));
            match (op, a, b) {
                (BinaryOp::Add, Scalar(a), Scalar(b)) => Scalar(a + b),
                (BinaryOp::Sub, Scalar(a), Scalar(b)) => Scalar(a - b),
                (BinaryOp::Mul, Scalar(a), Scalar(b)) => Scalar(a * b),
                (BinaryOp::Div, Scalar(a), Scalar(b)) => Scalar(a / b),
                (BinaryOp::Add, Vector(a), Vector(b)) => Vector(std::array::from_fn(|i| a[i] + b[i])),
                (BinaryOp::Sub, Vector(a), Vector(b)) => Vector(std::array::from_fn(|i| a[i] - b[i])),
                (BinaryOp::Mul, Scalar(s), Vector(v)) | (BinaryOp::Mul, Vector(v), Scalar(s)) => {
                    Vector(v.map(|c| s * c))
                }
                (BinaryOp::Div, Vector(v), Scalar(s)) => Vector(v.map(|c| c / s)),
                _ => Scalar(f64::NAN),
            }
        }
        Node::Call(f, args) => {
            let s = |k: usize| args.get(k).map_or(f64::NAN, |a| eval(a, inputs).scalar());
            let v = |k: usize| args.get(k).map_or([f64::NAN; 3], |a| eval(a, inputs).vector());
            Scalar(match f {
                Function::Abs => s(0).abs(),
                Function::Sqrt => s(0).sqrt(),
                Function::Log => s(0).ln(),
                Function::Exp => s(0).exp(),
                Function::Sin => s(0).sin(),
                Function::Cos => s(0).cos(),
                Function::Pow => s(0).powf(s(1)),
                Function::Min => s(0).min(s(1)),
                Function::Max => s(0).max(s(1)),
                // GLSL's clamp: min(max(a, lo), hi).
                Function::Clamp => s(0).max(s(1)).min(s(2)),
                Function::Length => {
                    let a = v(0);
                    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
                }
                Function::Dot => {
                    let (a, b) = (v(0), v(1));
                    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
                }
            })
        }
    }
}

impl Expression {
    /// The expression's value at one point, in f64.
    pub fn eval(&self, inputs: &Inputs<'_>) -> f64 {
        eval(&self.root, inputs).scalar()
    }
}

/// First-order error bounds of what an expression reads, for [`Expression::rounding_bound`].
#[derive(Debug, Clone, Copy)]
pub struct InputErrors<'a> {
    /// Bound on |device − exact| of slot k's value.
    pub values: &'a [f64],
    /// Bound on the Euclidean norm of device − exact of slot k's gradient.
    pub gradients: &'a [f64],
    /// Bound on variable k's error (vectors: the norm).
    pub variables: &'a [f64],
}

const EPS: f64 = f32::EPSILON as f64;

/// A value and its error bound (vectors: the norm of the error).
#[derive(Clone, Copy)]
enum Bounded {
    Scalar(f64, f64),
    Vector([f64; 3], f64),
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn bound(node: &Node, inputs: &Inputs<'_>, errors: &InputErrors<'_>) -> Bounded {
    use Bounded::{Scalar, Vector};
    let inf = f64::INFINITY;
    match node {
        Node::Number(v) => Scalar(*v, EPS * v.abs()),
        Node::Variable(k, ty) => {
            let v = inputs.variables.get(*k).copied().unwrap_or([f64::NAN; 3]);
            let e = errors.variables.get(*k).copied().unwrap_or(inf);
            if *ty == super::Type::Scalar {
                Scalar(v[0], e)
            } else {
                Vector(v, e)
            }
        }
        Node::Value(k) => Scalar(inputs.values[*k], errors.values[*k]),
        Node::Gradient(k) => Vector(inputs.gradients[*k], errors.gradients[*k]),
        Node::Negate(a) => match bound(a, inputs, errors) {
            Scalar(v, e) => Scalar(-v, e),
            Vector(v, e) => Vector(v.map(|c| -c), e),
        },
        Node::Component(a, c) => match bound(a, inputs, errors) {
            Vector(v, e) => Scalar(v[*c], e),
            Scalar(..) => Scalar(f64::NAN, inf),
        },
        Node::Binary(op, a, b) => {
            let (a, b) = (bound(a, inputs, errors), bound(b, inputs, errors));
            match (op, a, b) {
                (BinaryOp::Add | BinaryOp::Sub, Scalar(x, ex), Scalar(y, ey)) => {
                    let r = if *op == BinaryOp::Add { x + y } else { x - y };
                    Scalar(r, ex + ey + EPS * r.abs())
                }
                (BinaryOp::Add | BinaryOp::Sub, Vector(x, ex), Vector(y, ey)) => {
                    let s = if *op == BinaryOp::Add { 1.0 } else { -1.0 };
                    let r = std::array::from_fn(|i| x[i] + s * y[i]);
                    Vector(r, ex + ey + EPS * norm(r))
                }
                (BinaryOp::Mul, Scalar(x, ex), Scalar(y, ey)) => {
                    Scalar(x * y, x.abs() * ey + y.abs() * ex + ex * ey + EPS * (x * y).abs())
                }
                (BinaryOp::Mul, Scalar(s, es), Vector(v, ev))
                | (BinaryOp::Mul, Vector(v, ev), Scalar(s, es)) => {
                    let r = v.map(|c| s * c);
                    Vector(r, s.abs() * ev + norm(v) * es + es * ev + EPS * norm(r))
                }
                (BinaryOp::Div, Scalar(x, ex), Scalar(y, ey)) => {
                    let r = x / y;
                    let e = if y.abs() > ey { (ex + r.abs() * ey) / (y.abs() - ey) } else { inf };
                    // GLSL's division: 2.5 ulp.
                    Scalar(r, e + 3.0 * EPS * r.abs())
                }
                (BinaryOp::Div, Vector(v, ev), Scalar(y, ey)) => {
                    let r = v.map(|c| c / y);
                    let e = if y.abs() > ey { (ev + norm(r) * ey) / (y.abs() - ey) } else { inf };
                    Vector(r, e + 3.0 * EPS * norm(r))
                }
                _ => Scalar(f64::NAN, inf),
            }
        }
        Node::Call(f, args) => {
            let arg = |k: usize| args.get(k).map(|a| bound(a, inputs, errors));
            let s = |k: usize| match arg(k) {
                Some(Scalar(v, e)) => (v, e),
                _ => (f64::NAN, inf),
            };
            let v = |k: usize| match arg(k) {
                Some(Vector(v, e)) => (v, e),
                _ => ([f64::NAN; 3], inf),
            };
            // Device precision from the Vulkan specification's "Precision and Operation of
            // SPIR-V Instructions": sqrt ~ 1/inversesqrt (2 ulp + division), exp 3 + 2|x|
            // ulp, log 3 ulp outside [0.5, 2] and 2⁻²¹ absolute inside, sin/cos 2⁻¹¹ absolute
            // in [−π, π] (undefined outside: bound infinite), pow inherited from
            // exp2(y log2 x).
            let (value, e) = match f {
                Function::Abs => {
                    let (a, e) = s(0);
                    (a.abs(), e)
                }
                Function::Sqrt => {
                    let (a, e) = s(0);
                    let r = a.sqrt();
                    let lo = (a - e).max(0.0).sqrt();
                    (r, e.sqrt().min(e / (r + lo)) + 5.0 * EPS * r)
                }
                Function::Log => {
                    let (a, e) = s(0);
                    let r = a.ln();
                    let device = if (0.5..=2.0).contains(&a) { 2f64.powi(-21) } else { 3.0 * EPS * r.abs() };
                    (r, if a - e > 0.0 { (a / (a - e)).ln() + device } else { inf })
                }
                Function::Exp => {
                    let (a, e) = s(0);
                    let r = a.exp();
                    (r, r * (e.exp() - 1.0) + (3.0 + 2.0 * a.abs()) * EPS * r)
                }
                Function::Sin | Function::Cos => {
                    let (a, e) = s(0);
                    let r = if *f == Function::Sin { a.sin() } else { a.cos() };
                    let inside = a.abs() + e <= std::f64::consts::PI;
                    (r, if inside { e + 2f64.powi(-11) } else { inf })
                }
                Function::Pow => {
                    let ((a, ea), (b, eb)) = (s(0), s(1));
                    let r = a.powf(b);
                    if a - ea <= 0.0 {
                        (r, inf)
                    } else {
                        let y = b * a.log2();
                        let log2 = if (0.5..=2.0).contains(&a) {
                            2f64.powi(-21)
                        } else {
                            3.0 * EPS * a.log2().abs()
                        };
                        let ey = b.abs() * log2 + EPS * y.abs();
                        let input = b.abs() * ea / (a - ea) + a.ln().abs() * eb;
                        (
                            r,
                            r.abs() * (input + std::f64::consts::LN_2 * ey)
                                + (3.0 + 2.0 * y.abs()) * EPS * r.abs(),
                        )
                    }
                }
                Function::Min | Function::Max => {
                    let ((a, ea), (b, eb)) = (s(0), s(1));
                    (if *f == Function::Min { a.min(b) } else { a.max(b) }, ea.max(eb))
                }
                Function::Clamp => {
                    let ((a, ea), (lo, elo), (hi, ehi)) = (s(0), s(1), s(2));
                    (a.max(lo).min(hi), ea.max(elo).max(ehi))
                }
                Function::Length => {
                    let (a, e) = v(0);
                    let r = norm(a);
                    (r, e + 6.0 * EPS * r)
                }
                Function::Dot => {
                    let ((a, ea), (b, eb)) = (v(0), v(1));
                    let (na, nb) = (norm(a), norm(b));
                    (
                        a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
                        na * eb + nb * ea + ea * eb + 3.0 * EPS * na * nb,
                    )
                }
            };
            Scalar(value, e)
        }
    }
}

impl Expression {
    /// A first-order bound on |device − exact| of the expression's value, from bounds on what
    /// it reads (`errors`), propagated through every operation (|a|e_b + |b|e_a + e_a e_b for
    /// a product, e / (|b| − e_b) for a quotient, …) plus each operation's own f32 rounding
    /// and the device precision the Vulkan specification allows its built-in functions.
    /// Infinite where a function leaves its domain within the error (log near 0, sin beyond
    /// ±π): such points are not comparable.
    pub fn rounding_bound(&self, inputs: &Inputs<'_>, errors: &InputErrors<'_>) -> f64 {
        match bound(&self.root, inputs, errors) {
            Bounded::Scalar(_, e) => e,
            Bounded::Vector(..) => f64::INFINITY,
        }
    }
}
