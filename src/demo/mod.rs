//! The first real passes, each with its CPU f64 reference: `y ← a·x + y` on the compute side
//! ([`axpy`]), and a graphics pass whose fragment shader evaluates a polynomial of the fragment
//! position ([`field`]). `galerkin demo` runs them from a TOML scene ([`scene`]) and writes
//! `out/*.png` through [`run`], with every capability's part ([`capabilities`]), each
//! checked against its CPU reference.

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/demo/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_demo.rs"));
}
pub mod axpy;
pub mod capabilities;
pub mod field;
pub mod polynomial;
pub mod run;
pub mod scene;
#[cfg(feature = "viewer")]
pub mod viewer;
