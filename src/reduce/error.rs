//! Errors of model reduction. Each names the tensor, input, basis or axis at fault.

use crate::tensor::TensorError;

/// What can go wrong while describing, reducing or evaluating a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReduceError {
    /// An expression names a tensor the model does not declare.
    #[error("unknown tensor `{0}`")]
    UnknownTensor(String),
    /// An expression names an input the model does not declare.
    #[error("unknown input `{0}`")]
    UnknownInput(String),
    /// A value for an input was not given.
    #[error("no value given for input `{0}`")]
    MissingInput(String),
    /// No basis of this name was given, but an axis needs it.
    #[error("no basis `{basis}` (needed by {needed_by})")]
    UnknownBasis {
        /// The basis name.
        basis: String,
        /// What needs it.
        needed_by: String,
    },
    /// Two axes that meet in a contraction or a sum carry different bases.
    #[error("{what}: axis {axis} is in basis `{expected}` but meets a value in basis `{found}`")]
    BasisMismatch {
        /// The expression.
        what: String,
        /// The axis of the tensor being contracted (or summed).
        axis: usize,
        /// Its basis.
        expected: String,
        /// The other side's basis.
        found: String,
    },
    /// §4: a matrix that is inverted or rooted must be reduced with the same basis on both axes.
    #[error(
        "{what}: the {op} needs the same basis on both axes (§4), but axis 0 is in `{axis0}` and axis 1 in `{axis1}`"
    )]
    SameBasisRequired {
        /// "inverse" or "root".
        op: &'static str,
        /// The matrix expression (names the tensor).
        what: String,
        /// Basis of axis 0.
        axis0: String,
        /// Basis of axis 1.
        axis1: String,
    },
    /// An operation that needs a matrix got a value of another order.
    #[error("{what}: the {op} needs a matrix, this value has {order} axes")]
    NotAMatrix {
        /// "inverse" or "root".
        op: &'static str,
        /// The expression.
        what: String,
        /// Its order.
        order: usize,
    },
    /// A contraction names an axis the tensor lacks, twice, or contracts with a non-vector.
    #[error("{what}: {detail}")]
    BadContraction {
        /// The expression.
        what: String,
        /// What is wrong.
        detail: String,
    },
    /// A declared tensor's axis list disagrees with its data, or an axis length disagrees with
    /// its basis or with another axis of the same basis.
    #[error("tensor `{tensor}` axis {axis} (basis `{basis}`): {detail}")]
    AxisLength {
        /// The tensor.
        tensor: String,
        /// The axis.
        axis: usize,
        /// Its basis name.
        basis: String,
        /// What is wrong.
        detail: String,
    },
    /// An input vector has the wrong length for its basis.
    #[error("input `{input}` (basis `{basis}`) has {found} values, expected {expected}")]
    InputLength {
        /// The input.
        input: String,
        /// Its basis.
        basis: String,
        /// Expected length.
        expected: usize,
        /// Given length.
        found: usize,
    },
    /// A basis is malformed (not a matrix, more columns than rows, not orthonormal).
    #[error("basis `{basis}`: {detail}")]
    BadBasis {
        /// The basis.
        basis: String,
        /// What is wrong.
        detail: String,
    },
    /// A reduced-model file that cannot be read or written.
    #[error("{path}: {detail}")]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        detail: String,
    },
    /// The device failed (out of memory, device lost) or a request exceeds its limits.
    #[error("{context}: {cause}")]
    Device {
        /// What was being done.
        context: String,
        /// The device layer's error, typed so a host can tell device loss and out-of-memory
        /// from a bad input ([`crate::gpu::GpuFailure`]).
        cause: crate::gpu::GpuError,
    },
    /// A tensor operation failed (singular matrix, non-SPD root, …).
    #[error("{context}: {cause}")]
    Tensor {
        /// Where.
        context: String,
        /// The failure (shown in the message, so not also the error's `source`).
        cause: TensorError,
    },
    /// A collective operation between ranks failed, or another rank failed and stopped all.
    #[error("{context}: {cause}")]
    Ranks {
        /// What was being done.
        context: String,
        /// The rank and its message (shown in the message, so not also the error's `source`).
        cause: super::ranks::RanksError,
    },
}

impl crate::gpu::GpuFailure for ReduceError {
    fn gpu_error(&self) -> Option<&crate::gpu::GpuError> {
        match self {
            Self::Device { cause, .. } => Some(cause),
            _ => None,
        }
    }
}

impl ReduceError {
    /// Wraps a device failure met while doing `context` (for `map_err`).
    pub fn device(context: &str) -> impl FnOnce(crate::gpu::GpuError) -> Self + '_ {
        move |cause| Self::Device { context: context.to_string(), cause }
    }
}
