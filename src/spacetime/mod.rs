//! Pixel-exact rendering of spacetime discontinuous-Galerkin solutions (seed 003).
//!
//! A spacetime mesh (vertices (x, y, t), tetrahedra) carries per element a cubic displacement
//! in local coordinates ([`cubic`]). To show time `t`, the mesh is sliced with the plane
//! `t = const` ([`mod@slice`]; a compute pass on the device), and every slice polygon is drawn with
//! the height `|v|` computed per vertex and the strain energy density and the exact normal of
//! the height field computed per pixel ([`SpacetimeRenderer`]), its edges drawn again to fill
//! cracks between discontinuous neighbours (§4.3).
//!
//! Data: [`SpacetimeMesh`] (f64, shared vertices) for generation and references;
//! [`ElementRecord`]s sorted by lowest time in a [`SpacetimeData`] for rendering, in memory or
//! memory-mapped from a `.gst` file ([`gst`]); VTK `.vtu` files ([`vtu`]). Data sets are
//! generated ([`generate`]: structured meshes; [`tent`]: tent pitching; [`scenario`]: the
//! seed's crack, inclusion and booster scenarios): the fields are analytic, not solved.

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/spacetime/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_spacetime.rs"));
}
pub mod bar;
pub mod cubic;
pub mod data;
pub mod dataset;
mod error;
pub mod generate;
pub mod gst;
pub mod mesh;
pub mod picture;
pub mod record;
pub mod reference;
mod render;
pub mod scenario;
pub mod slice;
pub mod tent;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod vtu;

pub use cubic::{evaluate, LocalFrame, Material, PointFields, MONOMIALS};
pub use data::{DataSummary, SpacetimeData};
pub use error::SpacetimeError;
pub use mesh::{ElementField, SpacetimeMesh};
pub use record::ElementRecord;
pub use render::{
    FrameTimes, SliceLine, SlicePlan, SliceStats, SliceTriangle, SpacetimeDraw, SpacetimeRenderer,
    SpacetimeView,
};
