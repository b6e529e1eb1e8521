//! # galerkin
//!
//! A Rust engine on raw Vulkan (ash) for two things:
//!
//! 1. **Reduced simulation by non-polynomial Galerkin projection** (seed 000, Stanton et al.
//!    2013): functions built from tensor contractions, matrix inverses and matrix roots are
//!    model-reduced by premultiplying their tensors with bases.
//! 2. **Pixel-exact rendering of high-order solutions** (seeds 002 and 003): graphics
//!    pipelines evaluate each element's polynomial at every pixel.
//!
//! Data flows from files through plain Rust models with CPU f64 reference maths, is uploaded
//! once into [`gpu`] buffers and images, is processed by passes that record into a command
//! buffer they are handed, and leaves as images ([`render`]), tables or files.
//!
//! The layers: [`gpu`] (Vulkan, knows nothing of the maths), [`render`] (targets, images,
//! colour maps, camera, viewer), [`demo`] (the first passes with their CPU references),
//! [`mod@bench`] (the device's ceilings), [`tensor`] and [`reduce`] (seed 000 §3–4), [`spacetime`]
//! (seed 003), [`spectral`] (seed 002),
//! [`radiosity`] (seed 000 §8–9).

pub mod atomic_file;
pub mod bench;
pub mod demo;
pub mod expression;
pub mod fluid;
pub mod gpu;
pub mod limits;
pub mod mesh;
pub mod picture;
pub mod plot;
pub mod process;
pub mod radiosity;
pub mod reduce;
pub mod render;
pub mod scene_file;
pub mod spacetime;
pub mod spectral;
pub mod tensor;
pub mod vtk;
