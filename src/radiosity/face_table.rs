//! The per-face result of a radiosity solve as a table for other tools (`galerkin radiosity
//! render --faces FILE.csv`): one row per face with its part, kind, area, centroid and the
//! radiosity b (Eq. 14) per channel, every number in f64 printed so that it reads back to the
//! same bits (Rust's shortest round-trip form). Written whole or not at all
//! ([`crate::atomic_file`]).

use std::io::Write;
use std::path::Path;

use super::mesh::{FaceGeometry, FaceKind, SceneMesh};
use super::{RadiosityError, Rgb};

/// The table's header.
pub const HEADER: &str =
    "face,part,kind,area,centroid_x,centroid_y,centroid_z,radiosity_r,radiosity_g,radiosity_b";

/// A face kind's name in the table.
pub fn kind_name(kind: FaceKind) -> &'static str {
    match kind {
        FaceKind::Surface => "surface",
        FaceKind::Window => "window",
        FaceKind::Skylight => "skylight",
    }
}

/// Writes the table of `mesh` (with its `geometry`) and per-face `radiosity` to `path`.
pub fn write(
    path: &Path,
    mesh: &SceneMesh,
    geometry: &FaceGeometry,
    radiosity: &[Rgb],
) -> Result<(), RadiosityError> {
    let fail = |e: std::io::Error| RadiosityError::File { path: path.to_path_buf(), message: e.to_string() };
    if radiosity.len() != mesh.len() || geometry.areas.len() != mesh.len() {
        return Err(RadiosityError::Mesh(format!(
            "{}: {} faces, {} radiosity values, {} areas",
            path.display(),
            mesh.len(),
            radiosity.len(),
            geometry.areas.len()
        )));
    }
    let mut text = Vec::with_capacity(160 * (mesh.len() + 1));
    writeln!(text, "{HEADER}").map_err(fail)?;
    for (i, b) in radiosity.iter().enumerate() {
        let c = geometry.centroids[i];
        // Part names are the scene's own (OBJ object names): quoted where a comma or quote
        // would break the row.
        let part = mesh.part_of(i);
        let part = if part.contains([',', '"', '\n']) {
            format!("\"{}\"", part.replace('"', "\"\""))
        } else {
            part.to_string()
        };
        writeln!(
            text,
            "{i},{part},{},{},{},{},{},{},{},{}",
            kind_name(mesh.kind[i]),
            geometry.areas[i],
            c.x,
            c.y,
            c.z,
            b[0],
            b[1],
            b[2]
        )
        .map_err(fail)?;
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(fail)?;
    }
    crate::atomic_file::write(path, &text).map_err(fail)
}
