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
//! - [`render`]: the Vulkan renderer: planar meshes by per-fragment Newton inversion of the
//!   geometry map and evaluation; surfaces in 3D by adaptive tessellation on the device with a
//!   screen-space error bound; colour maps (linear or log), iso-lines, edge overdraw, the
//!   per-vertex baseline.
//! - [`vtu`]: VTK Lagrange cells in `.vtu` files.
//! - [`reference`]: the per-pixel check against the f64 reference (tests and demo).

pub mod basis;
pub mod error;
pub mod generate;
pub mod mesh;
pub mod proxy;
pub mod reference;
pub mod render;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod vtu;

pub use basis::{Basis1d, NodeSet, MAX_ORDER};
pub use error::SpectralError;
pub use mesh::{Field, Shape, SpectralMesh};
pub use render::{fit_camera, SpectralRenderer, SpectralView, View2d, INSIDE_TOLERANCE, MAX_TESSELLATION};

/// Loads a data set by its extension: `.vtu` (VTK Lagrange cells).
pub fn load(path: &std::path::Path) -> Result<SpectralMesh, SpectralError> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("vtu") => vtu::read(path),
        _ => Err(SpectralError::File {
            path: path.to_path_buf(),
            detail: "unknown extension: expected .vtu".into(),
        }),
    }
}
