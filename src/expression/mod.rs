//! Derived fields: small expressions over a solution (`--expr 'length(grad(u))'`), evaluated
//! **per pixel** from each element's exact polynomial — where ParaView's Calculator and GLVis
//! evaluate at vertices and interpolate.
//!
//! One parsed, type-checked [`Expression`] has two evaluations, tested to agree: the f64
//! interpreter ([`Expression::eval`], the reference and the colour range) and its translation
//! to a GLSL function ([`Expression::glsl`]) spliced into the renderer's fragment shader and
//! compiled at run time through the `shaderc` crate (feature `runtime-shaderc`,
//! [`spectral::compile_fragment`]).
//!
//! # The language
//! - numbers (`2`, `0.5`, `1e-3`), `+ - * /`, unary `-`, parentheses;
//! - spectral elements: `u`, the shown field; any other field of the file by its name
//!   (`pressure`), or by `field("name with spaces")`; `x`, `y`, `z`: the physical point; `t`:
//!   the step's time (other renderers name their own fields and variables: [`Scope`]);
//! - `grad(f)`: the physical gradient of a field (a 3-vector: on planar meshes z is 0, on
//!   surfaces it is tangential), from the element's polynomial and its geometry map, exact;
//!   `v.x`, `v.y`, `v.z`: a vector's components;
//! - `abs sqrt log exp sin cos` (one scalar), `pow min max` (two), `clamp(a, lo, hi)`,
//!   `length(v)`, `dot(v, w)`.
//!
//! Vectors add and subtract, scale by scalars and divide by them; anything else between a
//! vector and a scalar (`grad(u) + 1`) is a type error, and the whole expression must be a
//! scalar. `log`, `sqrt` and `pow` outside their domains give NaN in the reference and are
//! undefined on the device (GLSL); such pixels are not compared.

mod eval;
mod glsl;
mod parse;
pub mod spacetime;
pub mod spectral;
mod spectral_bound;

pub use eval::{physical_gradient, InputErrors, Inputs};

/// An error in an expression, naming its column (1-based, in characters).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("expression {text:?}, column {column}: {message}\n  {text}\n  {marker}^")]
pub struct ExpressionError {
    /// The expression as written.
    pub text: String,
    /// 1-based column of the offending character.
    pub column: usize,
    /// What is wrong there.
    pub message: String,
    marker: String,
}

impl ExpressionError {
    pub(crate) fn new(text: &str, column: usize, message: impl Into<String>) -> Self {
        Self {
            text: text.to_string(),
            column,
            message: message.into(),
            marker: " ".repeat(column.saturating_sub(1)),
        }
    }
}

/// The longest expression accepted (characters), and the deepest nesting of parentheses and
/// calls: bounds on what hostile input can make the parser and the shader compiler do.
pub const MAX_LENGTH: usize = 4096;
/// See [`MAX_LENGTH`].
pub const MAX_DEPTH: usize = 64;

/// A value's type in the language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Type {
    /// One number.
    Scalar,
    /// Three numbers (a gradient).
    Vector,
}

impl Type {
    fn name(self) -> &'static str {
        match self {
            Type::Scalar => "a scalar",
            Type::Vector => "a vector",
        }
    }
}

/// A field an expression reads: slot 0 is always the shown field (`u`); the others are the
/// file's fields named in the expression, in order of first appearance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Slot {
    /// `u`: whichever field is shown.
    Shown,
    /// A field of the file, by its index there (and its name, for messages).
    Named(usize, String),
}

/// Built-in functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Function {
    /// `abs`: |a|.
    Abs,
    /// `sqrt`: √a.
    Sqrt,
    /// `log`: natural logarithm.
    Log,
    /// `exp`: eᵃ.
    Exp,
    /// `sin`: sine (radians).
    Sin,
    /// `cos`: cosine (radians).
    Cos,
    /// `pow`: aᵇ.
    Pow,
    /// `min`: the lesser.
    Min,
    /// `max`: the greater.
    Max,
    /// `clamp`: min(max(a, lo), hi).
    Clamp,
    /// `length`: Euclidean length of a vector.
    Length,
    /// `dot`: dot product of two vectors.
    Dot,
}

impl Function {
    /// Every function: its name, argument types and result type.
    pub const ALL: [(Function, &'static str, &'static [Type], Type); 12] = [
        (Function::Abs, "abs", &[Type::Scalar], Type::Scalar),
        (Function::Sqrt, "sqrt", &[Type::Scalar], Type::Scalar),
        (Function::Log, "log", &[Type::Scalar], Type::Scalar),
        (Function::Exp, "exp", &[Type::Scalar], Type::Scalar),
        (Function::Sin, "sin", &[Type::Scalar], Type::Scalar),
        (Function::Cos, "cos", &[Type::Scalar], Type::Scalar),
        (Function::Pow, "pow", &[Type::Scalar, Type::Scalar], Type::Scalar),
        (Function::Min, "min", &[Type::Scalar, Type::Scalar], Type::Scalar),
        (Function::Max, "max", &[Type::Scalar, Type::Scalar], Type::Scalar),
        (Function::Clamp, "clamp", &[Type::Scalar, Type::Scalar, Type::Scalar], Type::Scalar),
        (Function::Length, "length", &[Type::Vector], Type::Scalar),
        (Function::Dot, "dot", &[Type::Vector, Type::Vector], Type::Scalar),
    ];

    fn by_name(name: &str) -> Option<(Function, &'static [Type], Type)> {
        Self::ALL.iter().find(|f| f.1 == name).map(|f| (f.0, f.2, f.3))
    }

    /// The function's name in the language (and in GLSL, where it is the same).
    pub fn name(self) -> &'static str {
        Self::ALL.iter().find(|f| f.0 == self).map_or("?", |f| f.1)
    }
}

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
}

/// A type-checked expression tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// A literal.
    Number(f64),
    /// A variable of the scope (its index in [`Scope::variables`], and its type).
    Variable(usize, Type),
    /// A field's value (its slot).
    Value(usize),
    /// A field's physical gradient (its slot).
    Gradient(usize),
    /// `-a`.
    Negate(Box<Node>),
    /// `a op b`.
    Binary(BinaryOp, Box<Node>, Box<Node>),
    /// `f(args)`.
    Call(Function, Vec<Node>),
    /// `v.x` (0), `v.y` (1), `v.z` (2).
    Component(Box<Node>, usize),
}

/// A parsed, type-checked scalar expression and the fields it reads.
#[derive(Debug, Clone, PartialEq)]
pub struct Expression {
    /// As the user wrote it.
    pub text: String,
    /// The tree.
    pub root: Node,
    /// The fields read, slot 0 first (always [`Slot::Shown`], read or not).
    pub slots: Vec<Slot>,
    /// The scope's variable names, in order (what [`Node::Variable`] indexes).
    pub variables: Vec<String>,
}

/// What names an expression may use: the shown field (`u` for spectral elements), the
/// file's other fields (gradable scalars, by name) and built-in variables.
#[derive(Debug, Clone, Copy)]
pub struct Scope<'a> {
    /// The shown field's name in the language (slot 0).
    pub shown: &'a str,
    /// The file's fields, in file order ([`Slot::Named`] indexes them).
    pub fields: &'a [String],
    /// Built-in variables and their types.
    pub variables: &'a [(&'a str, Type)],
}

/// The spectral renderer's variables: the physical point and the step's time.
pub const SPECTRAL_VARIABLES: [(&str, Type); 4] =
    [("x", Type::Scalar), ("y", Type::Scalar), ("z", Type::Scalar), ("t", Type::Scalar)];

impl Expression {
    /// Parses `text` for spectral elements: `u`, the file's fields (`fields`, in file order),
    /// x, y, z and t ([`Self::parse_in`]).
    pub fn parse(text: &str, fields: &[String]) -> Result<Self, ExpressionError> {
        parse::parse(text, &Scope { shown: "u", fields, variables: &SPECTRAL_VARIABLES })
    }

    /// Parses `text` in `scope`: a syntax error, an unknown name or a type error is reported
    /// with its column, and a vector-valued expression is refused (it cannot be
    /// colour-mapped).
    pub fn parse_in(text: &str, scope: &Scope<'_>) -> Result<Self, ExpressionError> {
        parse::parse(text, scope)
    }

    /// Whether slot `k`'s gradient is read (the device skips the derivative sums of the others).
    pub fn reads_gradient(&self, k: usize) -> bool {
        self.any(&|n| *n == Node::Gradient(k))
    }

    /// Whether the variable `name` appears.
    pub fn uses(&self, name: &str) -> bool {
        let Some(k) = self.variables.iter().position(|v| v == name) else { return false };
        self.any(&|n| matches!(n, Node::Variable(v, _) if *v == k))
    }

    /// Whether the shown field `u` is read (by value or gradient).
    pub fn reads_shown(&self) -> bool {
        self.any(&|n| matches!(n, Node::Value(0) | Node::Gradient(0)))
    }

    /// Whether any node of the tree satisfies `test`.
    fn any(&self, test: &dyn Fn(&Node) -> bool) -> bool {
        fn walk(n: &Node, test: &dyn Fn(&Node) -> bool) -> bool {
            test(n)
                || match n {
                    Node::Negate(a) | Node::Component(a, _) => walk(a, test),
                    Node::Binary(_, a, b) => walk(a, test) || walk(b, test),
                    Node::Call(_, args) => args.iter().any(|a| walk(a, test)),
                    _ => false,
                }
        }
        walk(&self.root, test)
    }
}

#[cfg(test)]
mod tests;
