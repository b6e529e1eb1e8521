//! Fluids on deforming simplicial meshes in the full space (seed 000 §5, Fig. 2 left): the
//! ground truth and training-data source of the reduced fluids.
//!
//! - [`operators`]: the volume, flux-to-momentum, advection, diffusion, divergence and
//!   boundary tensors as the reduction core's sparse tensors, and their direct per-cell
//!   evaluation (tested to agree);
//! - [`projection`]: the pressure projection of Eq. 10, hybridised into one symmetric system
//!   of face multipliers and solved by multigrid-preconditioned conjugate gradients;
//! - [`solver`]: the time step (induced flux, RK4 advection–diffusion, projection, flux to
//!   velocity), with the sign and −V̇u decisions documented there;
//! - [`scene`] and [`snapshots`]: TOML scenes and the streaming snapshot format; [`run`]: a
//!   simulation written as a snapshot directory;
//! - [`reduced`]: the reduced fluid of §6 (bases, reduced tensors, the reduced step, the
//!   Fig. 5 error study).

// Numerical code indexes several arrays by the same cell, face or axis.
#![allow(clippy::needless_range_loop)]

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/fluid/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_fluid.rs"));
}
pub mod bird;
pub mod cavity;
pub mod embedded;
mod error;
pub mod export;
pub mod gpu;
pub mod operators;
pub mod particles;
pub mod picture;
pub mod projection;
pub mod reduced;
pub mod render;
pub mod run;
pub mod scene;
pub mod snapshots;
pub mod solver;
#[cfg(feature = "viewer")]
pub mod viewer;
#[cfg(feature = "viewer")]
pub mod viewer_cavity;

pub use error::FluidError;
pub use solver::{Advected, FluidParams, FluidSolver, FluidState, StepReport};
