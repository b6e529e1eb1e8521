//! Non-polynomial Galerkin projection (seed 000 §3–4).
//!
//! A function `y = f(x)` is written as a composition ([`Expr`]) of the paper's three
//! operations — (i) tensor contraction `Q ⊗_k X`, (ii) matrix inverse `Q⁻¹`, (iii) SPD matrix
//! root `Q^(1/n)` — plus sums and differences, over named tensors whose every axis carries the
//! name of its basis ([`Model`]). The model evaluates in the full space (CPU f64). Given a basis
//! for every axis name ([`Bases`]), [`Model::reduce`] premultiplies every tensor by its bases
//! (Eq. 2, §4's table) and returns a [`ReducedModel`] that evaluates *exactly the same
//! sequence of operations* on the reduced tensors — so the reduced inverse is
//! `(B_qᵀ Q B_q)⁻¹` and the reduced root `(B_qᵀ Q B_q)^(1/n)`, as §4.2 requires. §4's rule that
//! an inverted or rooted matrix carries the same basis on both axes is checked before anything
//! is computed, and a violation names the tensor and its axes.
//!
//! This module knows nothing of fluids or radiosity: they use it.

mod basis;
pub mod effectivity;
mod error;
mod eval;
mod expr;
mod file;
mod gpu_eval;
pub mod greedy;
mod model;
mod pca;
mod premultiply;
pub mod provenance;
pub mod ranks;
mod reduced;
pub mod reductor;
mod snapshot_basis;
pub mod synthetic;

pub use basis::{Bases, Basis};
pub use error::ReduceError;
pub use expr::Expr;
pub(crate) use file::erased;
pub use file::{load_arrays, save_arrays, serialize, ModelExtras, FORMAT, VERSION};
pub use gpu_eval::{Backend, GpuReducedModel};
pub use model::{FullTensor, Model, ReduceOptions, StreamedTensor, TensorDecl};
pub use pca::{pca, pca_across, pca_on, pca_with, Pca, SnapshotFile, SnapshotFn, SnapshotSource, Truncation};
pub use premultiply::{
    premultiply_dense, premultiply_sparse, premultiply_sparse_gpu, premultiply_sparse_on,
    premultiply_sparse_with, premultiply_streamed, premultiply_streamed_together, AxisRows, BasisRows,
    PremultiplyOptions, PremultiplyPlan, TensorChunks, Unit,
};
pub use ranks::{Communicator, RanksError, SingleRank, ThreadRank, ThreadRanks};
pub use reduced::ReducedModel;
pub use snapshot_basis::{basis_grams, snapshot_grams, SnapshotBasis, SnapshotRows, Spectrum};
