//! Errors of tensor operations: shapes that do not fit, singular or non-SPD matrices. Each
//! names the operand and the axis.

/// What can go wrong in [`crate::tensor`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TensorError {
    /// An axis length does not match what the operation needs.
    #[error("{what}: axis {axis} has length {found}, expected {expected}")]
    Shape {
        /// The operand or operation.
        what: String,
        /// The axis.
        axis: usize,
        /// Required length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// An axis index beyond the tensor's order.
    #[error("{what}: axis {axis} does not exist in a tensor of order {order}")]
    NoSuchAxis {
        /// The operand.
        what: String,
        /// The axis asked for.
        axis: usize,
        /// The tensor's order.
        order: usize,
    },
    /// Data length disagrees with the shape.
    #[error("{what}: shape {shape:?} holds {expected} values but {found} were given")]
    DataLength {
        /// The operand.
        what: String,
        /// The shape.
        shape: Vec<usize>,
        /// Values the shape holds.
        expected: usize,
        /// Values given.
        found: usize,
    },
    /// A sparse coordinate outside the shape.
    #[error("{what}: entry {entry} has index {index} on axis {axis} of length {size}")]
    IndexOutOfRange {
        /// The tensor.
        what: String,
        /// Which nonzero.
        entry: usize,
        /// The axis.
        axis: usize,
        /// The index given.
        index: usize,
        /// The axis length.
        size: usize,
    },
    /// A matrix that must be square is not (or an operand is not a matrix).
    #[error("{what}: needs a square matrix, got shape {shape:?}")]
    NotSquare {
        /// The operand.
        what: String,
        /// Its shape.
        shape: Vec<usize>,
    },
    /// A linear system could not be solved: the matrix is singular to working precision.
    #[error("{what}: the matrix is singular (pivot {pivot:e} at row {row})")]
    Singular {
        /// The operand.
        what: String,
        /// The row of the failing pivot.
        row: usize,
        /// Its size.
        pivot: f64,
    },
    /// A matrix root was asked of a matrix that is not symmetric positive (semi)definite.
    #[error("{what}: not symmetric positive {kind}: eigenvalue {eigenvalue:e}")]
    NotSpd {
        /// The operand.
        what: String,
        /// "definite" or "semidefinite", whichever the power needs.
        kind: &'static str,
        /// The offending eigenvalue.
        eigenvalue: f64,
    },
    /// A sparse factorisation failed (a non-positive pivot where the matrix must be definite).
    #[error("{what}: sparse factorisation failed: {detail}")]
    Factorisation {
        /// The operand.
        what: String,
        /// What the factoriser reported.
        detail: String,
    },
    /// A value that must be finite is not.
    #[error("{what}: {detail}")]
    NotFinite {
        /// The operand.
        what: String,
        /// Where.
        detail: String,
    },
    /// A tensor that cannot be stored as asked (the wrong order for the layout, or memory the
    /// system will not map).
    #[error("{what}: {detail}")]
    Storage {
        /// The operand.
        what: String,
        /// Why.
        detail: String,
    },
}
