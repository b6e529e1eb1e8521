//! Dense and sparse tensors with their CPU f64 reference operations (seed 000 §3–4).
//!
//! Conventions follow the paper: axes are numbered from 0 and axis 0 is the result axis;
//! `Q ⊗_k X` multiplies tensor `Q` along axis `k` by a vector (contraction: the order drops
//! by one) or by a matrix (the axis is replaced by the matrix's second axis) — see
//! [`Tensor::contract`] and [`Tensor::mode_product`]. Storage is row-major: the last axis
//! varies fastest.
//!
//! The operations here are written plainly: they are the test oracle for every fast path
//! (premultiplication, GPU kernels) and the documentation of the maths.

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/tensor/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_tensor.rs"));
}
pub mod amg;
mod csr;
mod dense;
mod error;
mod expm;
pub mod gpu;
mod linalg;
mod row_table;
mod sparse;
mod sparse_symmetric;

pub use csr::CsrMatrix;
pub use dense::{Scalar, Tensor};
pub use error::TensorError;
pub use expm::{expm, expm_faer, expm_krylov, KrylovReport, KRYLOV_MAX_DIM, KRYLOV_MAX_STEPS};
pub(crate) use linalg::{check_system, pivot_tolerance};
pub use linalg::{dot, matmul, solve, solve_many, spd_power, spd_power_apply, symmetric_eigen, transpose};
pub use row_table::RowTable;
pub use sparse::{distinct_permutations, SparseTensor};
pub use sparse_symmetric::{Factorisation, SparseSymmetricSolver, SymmetricPattern};
