//! The per-face result of a radiosity solve as a table for other tools (`galerkin radiosity
//! render --faces FILE.csv|FILE.npy`): one row per face with its part, kind, area, centroid and
//! the radiosity b (Eq. 14) per channel. CSV prints every f64 so that it reads back to the same
//! bits (Rust's shortest round-trip form); NPY (NumPy's format, through the `npyz` crate) holds
//! the numbers as a faces × 8 little-endian f64 array, columns [`NPY_COLUMNS`] (the part names
//! are in the CSV only). Written whole or not at all ([`crate::atomic_file`]).

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

/// The NPY table's columns (`kind`: 0 surface, 1 window, 2 skylight).
pub const NPY_COLUMNS: [&str; 8] =
    ["kind", "area", "centroid_x", "centroid_y", "centroid_z", "radiosity_r", "radiosity_g", "radiosity_b"];

/// The table's format, from the path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TableFormat {
    /// Text, one row per face (`.csv`).
    Csv,
    /// NumPy's binary array (`.npy`).
    Npy,
}

impl TableFormat {
    /// `.csv` or `.npy` (any case), else a sentence saying so.
    pub fn of(path: &Path) -> Result<Self, String> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("csv") => Ok(Self::Csv),
            Some("npy") => Ok(Self::Npy),
            _ => Err(format!("{}: the face table is written as CSV (.csv) or NumPy (.npy)", path.display())),
        }
    }
}

/// Writes the table of `mesh` (with its `geometry`) and per-face `radiosity` to `path`, in the
/// format its extension names ([`TableFormat::of`]).
pub fn write(
    path: &Path,
    mesh: &SceneMesh,
    geometry: &FaceGeometry,
    radiosity: &[Rgb],
) -> Result<(), RadiosityError> {
    let fail = |e: std::io::Error| RadiosityError::File { path: path.to_path_buf(), message: e.to_string() };
    let format = TableFormat::of(path).map_err(RadiosityError::Mesh)?;
    if radiosity.len() != mesh.len() || geometry.areas.len() != mesh.len() {
        return Err(RadiosityError::Mesh(format!(
            "{}: {} faces, {} radiosity values, {} areas",
            path.display(),
            mesh.len(),
            radiosity.len(),
            geometry.areas.len()
        )));
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(fail)?;
    }
    if format == TableFormat::Npy {
        let rows = radiosity.iter().enumerate().flat_map(|(i, b)| {
            let c = geometry.centroids[i];
            let kind = match mesh.kind[i] {
                FaceKind::Surface => 0.0,
                FaceKind::Window => 1.0,
                FaceKind::Skylight => 2.0,
            };
            [kind, geometry.areas[i], c.x, c.y, c.z, b[0], b[1], b[2]]
        });
        let mut bytes = Vec::with_capacity(128 + 64 * mesh.len());
        let shape = [mesh.len() as u64, NPY_COLUMNS.len() as u64];
        use npyz::WriterBuilder;
        let mut npy = npyz::WriteOptions::<f64>::new()
            .default_dtype()
            .shape(&shape)
            .writer(&mut bytes)
            .begin_nd()
            .map_err(fail)?;
        npy.extend(rows).map_err(fail)?;
        npy.finish().map_err(fail)?;
        return crate::atomic_file::write(path, &bytes).map_err(fail);
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
    crate::atomic_file::write(path, &text).map_err(fail)
}
