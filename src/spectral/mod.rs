//! Pixel-exact rendering of spectral elements (seed 002, Peng & Forsberg): the element's
//! tensor-product polynomial is evaluated for every pixel instead of interpolating colours
//! between nodes.
//!
//! - [`basis`]: the 1D bases (Lagrange on GLL, equispaced or Gauss points; Bernstein), the
//!   twin of `shaders-glsl/include/lagrange.glsl`.
//! - [`mesh`]: quadrilateral elements with curved geometry and fields over time steps; the CPU
//!   f64 reference (map, inverse map, values), twin of `spectral_element.glsl`.
//! - [`generate`]: synthetic data sets (straight and curved planar meshes, analytic fields).
//! - [`proxy`]: what is drawn — proxies that contain each curved element, node grids, edges.
//! - [`render`]: the Vulkan renderer: per-fragment Newton inversion of the geometry map and
//!   evaluation, colour maps (linear or log), iso-lines, edge overdraw, the per-vertex baseline.

pub mod basis;
pub mod error;
pub mod generate;
pub mod mesh;
pub mod proxy;
pub mod reference;
pub mod render;
pub mod vtu;

pub use basis::{Basis1d, NodeSet, MAX_ORDER};
pub use error::SpectralError;
pub use mesh::{Field, Shape, SpectralMesh};
pub use render::{SpectralRenderer, SpectralView, View2d, INSIDE_TOLERANCE};
