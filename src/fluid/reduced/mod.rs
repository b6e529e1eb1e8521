//! Reduced fluids (seed 000 §6, Fig. 2 right): the full solver's step Galerkin-projected onto
//! bases learned from its own snapshots, so a frame costs a few hundred dimensions' work.
//!
//! - [`study`] and [`plot`]: §7.1's one-step error study and its Fig. 5 plots;
//! - [`training`]: a training set, the snapshot directories of full runs on one mesh;
//! - [`bases`]: `B_f`, `B_u = B_p`, `B_g`, `B_h` by streamed PCA, `B_d` by constraint reduction;
//! - [`example`]: the small tunnel's training runs, for the demo, benchmarks and tests;
//! - [`indicator`]: a per-frame error indicator of a reduced run, without the full run (one
//!   full step per measured step);
//! - [`unseen`]: a per-frame error indicator from reduced quantities alone (every step, for
//!   `O(m_f²)`);
//! - [`induced`]: the induced flux as a tensor in the stacked geometry, for driven motions;
//! - [`compare`]: a reduced run against the full run of the same motion (energy, error);
//! - [`exact_projection`]: the projection's normal matrix from the full space;
//! - [`diagnose`]: a reduced step split into its stages, each against the full solver's;
//! - [`cavity_motion`]: the cavity's reduced geometry from its compressions, at run time;
//! - [`model`]: §6.2's reduced tensors premultiplied by the core, and the model file;
//! - [`pipeline`]: a scene to a model in one resumable command (runs, bases, tensors);
//! - [`particles`]: marker particles from the reduced state (Eq. 13), never the full one;
//! - [`run`]: a reduced run under a motion, lifted to a snapshot directory;
//! - [`step`]: the reduced step (flux combination, matrix exponential, constrained
//!   projection, conversion to velocity).
//!
//! The model is the projection of exactly the step [`crate::fluid::solver`] takes — its
//! dissipative Laplacian, the minus sign of advection, the −V̇u term and the induced flux
//! integrated over the frame — not of the equations as printed; [`model`] and [`step`] say
//! where the two differ.

pub mod bases;
pub mod cavity_motion;
pub mod compare;
mod dense;
pub mod diagnose;
pub mod exact_projection;
pub mod example;
pub mod indicator;
pub mod induced;
pub mod model;
mod model_file;
pub mod particles;
pub mod pipeline;
pub mod plot;
pub mod run;
pub mod step;
pub mod study;
pub mod training;
pub mod unseen;

pub use bases::{BasisReport, BasisSizes, FluidBases, ProjectedGeometry};
pub use cavity_motion::{CavityMotion, CompressionSchedule};
pub use model::{MeshFingerprint, MeshOf, ReducedFluidModel, Trajectory};
pub use pipeline::{train_scene, train_scene_across, SceneTraining, TrainingEvent};
pub use run::{run_driven, run_paced, run_reduced, write_lifted, ReducedMotion, ReducedRun, PACE_RANGE};
pub use step::{Exponential, FluxCombination, ReducedFluid, ReducedState, ReducedStepReport};
pub use study::{one_step_errors, ErrorStudy, SizeErrors};
pub use training::TrainingSet;
