//! Pixel-exact rendering of spectral elements (seed 002, Peng & Forsberg): the element's
//! tensor-product polynomial is evaluated for every pixel instead of interpolating colours
//! between nodes.
//!
//! - [`basis`]: the 1D bases (Lagrange on GLL, equispaced or Gauss points; Bernstein), the
//!   twin of `shaders-glsl/include/lagrange.glsl`.
//! - [`mesh`]: quadrilateral, hexahedral and (planar) Lagrange triangle elements with curved
//!   geometry and fields over time steps; the CPU f64 reference (map, inverse map, values),
//!   twin of `spectral_element.glsl`.
//! - [`simplex`]: Lagrange triangles and tetrahedra of orders 1–10 (VTK's node order,
//!   Silvester's basis), twin of `spectral_simplex.glsl`; [`simplex_mesh`]: the plain f64
//!   evaluation of `.vtu` simplices the tests compare against.
//! - [`generate`]: synthetic data sets (straight and curved planar meshes, analytic fields).
//! - [`proxy`]: what is drawn — proxies that contain each curved element, node grids, edges.
//! - [`render`]: the Vulkan renderer: planar meshes by per-fragment Newton inversion of the
//!   geometry map and evaluation; surfaces in 3D by adaptive tessellation on the device with a
//!   screen-space error bound; colour maps (linear or log), iso-lines, edge overdraw, the
//!   per-vertex baseline.
//! - [`vtu`]: VTK Lagrange cells in `.vtu` files; [`mfem`]: MFEM meshes, GridFunctions and
//!   GLVis solution streams.
//! - [`mod@reference`]: the per-pixel check against the f64 reference (tests and demo).

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/spectral/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_spectral.rs"));
}
pub mod basis;
pub mod collection;
pub mod error;
pub mod generate;
pub mod gradient;
pub mod iso_reference;
pub mod mesh;
pub mod mfem;
pub mod mfem_simplex;
mod mfem_topology;
pub mod picture;
pub mod proxy;
pub mod pvtu;
pub mod reference;
pub mod render;
pub mod simplex;
pub mod simplex_mesh;
pub mod transfer;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod volume_reference;
pub mod vtu;

pub use basis::{Basis1d, NodeSet, MAX_ORDER};
pub use error::SpectralError;
pub use mesh::{Field, Shape, SpectralMesh};
pub use render::{fit_camera, SpectralRenderer, SpectralView, View2d, INSIDE_TOLERANCE, MAX_TESSELLATION};

/// Loads a data set: a `.vtu` file (VTK Lagrange cells), a `.pvtu` of `.vtu` pieces
/// ([`pvtu`]), a `.pvd` collection or `.vtu.series`
/// of them (a time series, [`collection`]), a GLVis "solution" stream (a file
/// starting with `solution`), or an MFEM mesh with `grid_functions` as the time steps of one
/// field named after the first GridFunction file's stem.
pub fn load(
    path: &std::path::Path,
    grid_functions: &[std::path::PathBuf],
) -> Result<SpectralMesh, SpectralError> {
    let name = path.to_string_lossy().to_ascii_lowercase();
    let series = name.ends_with(".pvd") || name.ends_with(".vtu.series");
    if series || name.ends_with(".pvtu") || name.ends_with(".vtu") {
        if !grid_functions.is_empty() {
            return Err(SpectralError::Missing(
                "GridFunction files go with MFEM meshes, not .vtu, .pvtu, .pvd or .vtu.series files".into(),
            ));
        }
        return if series { collection::read_collection(path) } else { pvtu::read_vtu_or_pieces(path) };
    }
    let head = std::fs::read(path)
        .map_err(|e| SpectralError::File { path: path.to_path_buf(), detail: e.to_string() })?;
    let first = String::from_utf8_lossy(&head[..head.len().min(64)]).trim_start().to_string();
    if first.starts_with("solution") {
        let (mesh, gf) = mfem::read_solution(path)?;
        let mut steps = vec![gf];
        for g in grid_functions {
            steps.push(mfem::read_grid_function(g)?);
        }
        return mfem::to_spectral(&mesh, &[("solution".to_string(), steps)]);
    }
    if first.starts_with("MFEM mesh") {
        let mesh = mfem::read_mesh(path)?;
        if grid_functions.is_empty() {
            return Err(SpectralError::File {
                path: path.to_path_buf(),
                detail: "an MFEM mesh without fields: give its GridFunction files with --gf".into(),
            });
        }
        let steps =
            grid_functions.iter().map(|g| mfem::read_grid_function(g)).collect::<Result<Vec<_>, _>>()?;
        let name = grid_functions[0].file_stem().and_then(|s| s.to_str()).unwrap_or("field").to_string();
        return mfem::to_spectral(&mesh, &[(name, steps)]);
    }
    Err(SpectralError::File {
        path: path.to_path_buf(),
        detail:
            "not a .vtu, .pvtu or .pvd file, an MFEM mesh (\"MFEM mesh v1.0\") or a GLVis solution stream (\"solution\")"
                .into(),
    })
}
