//! Tensor operations on the device: the shared-memory tiled SGEMM
//! (`shaders-glsl/tensor/gemm.comp`), because every reduced-space contraction of a batch is a
//! GEMM once the batch's Khatri–Rao rows are formed (see [`crate::reduce::GpuReducedModel`]),
//! and the batched dense solve (`shaders-glsl/tensor/lu_solve.comp`) for the matrix inverses
//! of seed 000 §4 applied to vectors.

mod gemm;
mod solve;

pub use gemm::{Gemm, GemmBinding, GemmShape, GEMM_KT, GEMM_TILE};
pub use solve::BatchedSolve;
