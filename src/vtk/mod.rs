//! VTK XML unstructured grids (`.vtu`): the container, shared by the spacetime and spectral
//! data sets (each module maps its own cells and arrays onto it).
//!
//! Writing uses file version 2.2 and appended raw binary (`header_type="UInt64"`), to a unique temporary renamed when
//! complete. Reading accepts everything `vtkXMLUnstructuredGridWriter` (VTK 9) writes:
//! `ascii`, inline `binary` (base64) and `appended` data (raw or base64), UInt32 or UInt64
//! block headers, uncompressed or compressed with zlib, LZ4 or LZMA ([`encoding`]; tested on
//! files VTK itself wrote, `scripts/vtk-fixtures.py`); one `<Piece>`. Counts are checked
//! against [`MAX_COUNT`] and every compressed array against the size its `<Piece>` gives it
//! before anything is inflated. Every error names the file and, for data errors, the array.

pub mod encoding;

use std::io::Write;
use std::path::{Path, PathBuf};

use encoding::{base64_runs, numbers, type_size, Compressor, Framing};

/// The largest `NumberOfPoints` or `NumberOfCells` read (2³¹): a larger count is refused
/// before anything is allocated for it.
pub const MAX_COUNT: usize = crate::limits::MAX_COUNT as usize;

/// The most nodes per cell a `connectivity` array may average (VTK's Lagrange hexahedra of
/// order 9 have 1,000): bounds that array's size before it is inflated.
pub const MAX_NODES_PER_CELL: usize = 1000;
/// A problem with a `.vtu` file: the file and what is wrong.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {detail}")]
pub struct VtkError {
    /// The file.
    pub path: PathBuf,
    /// What is wrong.
    pub detail: String,
}

fn err(path: &Path, detail: impl Into<String>) -> VtkError {
    VtkError { path: path.to_path_buf(), detail: detail.into() }
}

/// One `<DataArray>` as numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    /// Its section: `Points`, `Cells`, `PointData`, `CellData` or `FieldData` (only its
    /// `TimeValue` is read).
    pub section: String,
    /// Its `Name` (`Points` for the points).
    pub name: String,
    /// `NumberOfComponents`.
    pub components: usize,
    /// The values, tuple by tuple.
    pub values: Vec<f64>,
}

/// The single piece of an unstructured grid, every array read.
#[derive(Clone, Debug, PartialEq)]
pub struct UnstructuredGrid {
    /// The file it came from (for errors).
    pub path: PathBuf,
    /// `NumberOfPoints`.
    pub points: usize,
    /// `NumberOfCells`.
    pub cells: usize,
    /// Every data array of the piece.
    pub arrays: Vec<DataArray>,
    /// The `<VTKFile>`'s `version` as (major, minor) (`(0, 1)` when absent): VTK changed the
    /// node order of Lagrange hexahedra at 2.2.
    pub version: (u32, u32),
}

impl UnstructuredGrid {
    /// The array `name` of `section`, if present.
    pub fn array(&self, section: &str, name: &str) -> Option<&DataArray> {
        self.arrays.iter().find(|a| a.section == section && (a.name == name || section == "Points"))
    }

    /// The array `name` of `section` with `components` per tuple and `tuples` tuples, or an
    /// error naming the file and array.
    pub fn require(
        &self,
        section: &str,
        name: &str,
        components: usize,
        tuples: usize,
    ) -> Result<&[f64], VtkError> {
        let a = self
            .array(section, name)
            .ok_or_else(|| err(&self.path, format!("no {section} array {name:?}")))?;
        if a.components != components || a.values.len() != components * tuples {
            return Err(err(
                &self.path,
                format!(
                    "array {name}: {} values in {} components, expected {tuples} × {components}",
                    a.values.len(),
                    a.components
                ),
            ));
        }
        Ok(&a.values)
    }

    /// Like [`Self::require`], `None` when the array is absent.
    pub fn optional(
        &self,
        section: &str,
        name: &str,
        components: usize,
        tuples: usize,
    ) -> Result<Option<&[f64]>, VtkError> {
        match self.array(section, name) {
            None => Ok(None),
            Some(_) => self.require(section, name, components, tuples).map(Some),
        }
    }

    /// An error about this file.
    pub fn error(&self, detail: impl Into<String>) -> VtkError {
        err(&self.path, detail)
    }
}

/// Values of an array to write.
pub enum Values {
    /// `Float64`.
    F64(Vec<f64>),
    /// `Int64`.
    I64(Vec<i64>),
    /// `Int32`.
    I32(Vec<i32>),
    /// `UInt8`.
    U8(Vec<u8>),
}

impl Values {
    fn vtk_type(&self) -> &'static str {
        match self {
            Self::F64(_) => "Float64",
            Self::I64(_) => "Int64",
            Self::I32(_) => "Int32",
            Self::U8(_) => "UInt8",
        }
    }

    fn bytes(&self) -> Vec<u8> {
        match self {
            Self::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Self::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Self::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Self::U8(v) => v.clone(),
        }
    }
}

/// An array to write: section (`Points`, `Cells`, `PointData`, `CellData`), name, components.
pub struct OutArray {
    /// Its section.
    pub section: &'static str,
    /// Its name.
    pub name: String,
    /// Components per tuple.
    pub components: usize,
    /// The values.
    pub values: Values,
}

/// Writes an unstructured grid of `points` points and `cells` cells with `arrays` (the
/// `Points` array, the `Cells` arrays `connectivity`, `offsets`, `types`, and any point and
/// cell data) to `path` as appended raw binary, whole or not at all
/// ([`crate::atomic_file`]);
/// `comment` goes into an XML comment at the top.
pub fn write(
    path: &Path,
    comment: &str,
    points: usize,
    cells: usize,
    arrays: &[OutArray],
) -> Result<(), VtkError> {
    let blobs: Vec<Vec<u8>> = arrays.iter().map(|a| a.values.bytes()).collect();
    let mut xml = format!(
        "<?xml version=\"1.0\"?>\n<!-- {comment} -->\n<VTKFile type=\"UnstructuredGrid\" version=\"2.2\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">\n"
    );
    let mut offset = 0u64;
    for section in ["Points", "Cells", "PointData", "CellData"] {
        let members: Vec<usize> = (0..arrays.len()).filter(|&k| arrays[k].section == section).collect();
        if members.is_empty() {
            continue;
        }
        // VTK takes a point-data array as a Bézier cell's weights only when the section names it.
        let rational = section == "PointData" && members.iter().any(|&k| arrays[k].name == "RationalWeights");
        let attribute = if rational { " RationalWeights=\"RationalWeights\"" } else { "" };
        xml.push_str(&format!("      <{section}{attribute}>\n"));
        for k in members {
            let a = &arrays[k];
            xml.push_str(&format!(
                "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>\n",
                a.values.vtk_type(),
                a.name,
                a.components
            ));
            offset += 8 + blobs[k].len() as u64;
        }
        xml.push_str(&format!("      </{section}>\n"));
    }
    xml.push_str("    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");
    // Blocks in section order, as the offsets were assigned.
    let order: Vec<usize> = ["Points", "Cells", "PointData", "CellData"]
        .iter()
        .flat_map(|s| (0..arrays.len()).filter(move |&k| arrays[k].section == *s))
        .collect();
    let mut file = crate::atomic_file::AtomicFile::create(path).map_err(|e| err(path, e.to_string()))?;
    let result = (|| -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(file.file());
        out.write_all(xml.as_bytes())?;
        for k in order {
            out.write_all(&(blobs[k].len() as u64).to_le_bytes())?;
            out.write_all(&blobs[k])?;
        }
        out.write_all(b"\n  </AppendedData>\n</VTKFile>\n")?;
        out.flush()
    })();
    // An error drops the file, which removes its temporary.
    result.map_err(|e| err(path, e.to_string()))?;
    file.commit().map_err(|e| err(path, e.to_string()))
}

/// Reads the one piece of the unstructured grid in `path`, with every data array.
pub fn read(path: &Path) -> Result<UnstructuredGrid, VtkError> {
    let bytes = std::fs::read(path).map_err(|e| err(path, e.to_string()))?;
    // Appended raw data are not XML: parse the text before them, closed.
    let appended_at = find(&bytes, b"<AppendedData");
    let text_end = appended_at.unwrap_or(bytes.len());
    let mut text = std::str::from_utf8(&bytes[..text_end])
        .map_err(|e| err(path, format!("not UTF-8 XML text at byte {}", e.valid_up_to())))?
        .to_string();
    if appended_at.is_some() {
        // The raw data end where the file closes: a file cut short (its closing tags gone) is
        // refused even where the arrays it declares happen to be complete.
        let tail = bytes.trim_ascii_end();
        if !tail.ends_with(b"</VTKFile>") || find(&bytes[text_end..], b"</AppendedData>").is_none() {
            return Err(err(
                path,
                "truncated: the appended data are not closed by </AppendedData> and </VTKFile>",
            ));
        }
        text.push_str("</VTKFile>");
    }
    let doc = roxmltree::Document::parse(&text).map_err(|e| err(path, format!("XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("UnstructuredGrid") {
        return Err(err(path, "not a VTK XML UnstructuredGrid file"));
    }
    if root.attribute("byte_order").is_some_and(|o| o != "LittleEndian") {
        return Err(err(path, "big-endian VTK files are not supported"));
    }
    let framing = Framing {
        header_u64: root.attribute("header_type") == Some("UInt64"),
        compressor: Compressor::from_attribute(root.attribute("compressor")).map_err(|e| err(path, e))?,
    };
    let version = match root.attribute("version") {
        None => (0, 1),
        Some(v) => {
            let mut parts = v.trim().split('.').map(|p| p.parse::<u32>());
            match (parts.next(), parts.next(), parts.next()) {
                (Some(Ok(major)), Some(Ok(minor)), None) => (major, minor),
                (Some(Ok(major)), None, None) => (major, 0),
                _ => return Err(err(path, format!("<VTKFile> version {v:?} is not MAJOR.MINOR"))),
            }
        }
    };
    // VTK 9 writes 2.2 (2.3 with its newer cells); a later major version may change what the
    // arrays mean (as 2.2 changed the Lagrange hexahedron's node order), so it is refused.
    if version.0 > 2 {
        return Err(err(
            path,
            format!(
                "<VTKFile> version {}.{}: this reader knows versions up to 2.x (VTK 9)",
                version.0, version.1
            ),
        ));
    }
    // The appended section: after the '_' that follows the opening tag.
    let appended = match appended_at {
        Some(at) => {
            let tag_end = find(&bytes[at..], b">")
                .map(|k| at + k)
                .ok_or_else(|| err(path, "unterminated <AppendedData>"))?;
            let tag = String::from_utf8_lossy(&bytes[at..tag_end]).to_string();
            let underscore = find(&bytes[tag_end..], b"_")
                .map(|k| tag_end + k + 1)
                .ok_or_else(|| err(path, "<AppendedData> without its '_' marker"))?;
            Some((tag.contains("encoding=\"base64\""), underscore))
        }
        None => None,
    };
    let pieces: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("Piece")).collect();
    if pieces.len() != 1 {
        return Err(err(path, format!("{} pieces; one is supported", pieces.len())));
    }
    let piece = pieces[0];
    let count = |name: &str| -> Result<usize, VtkError> {
        piece
            .attribute(name)
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| err(path, format!("<Piece> lacks a valid {name}")))
    };
    let (n_points, n_cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);
    for (name, n) in [("NumberOfPoints", n_points), ("NumberOfCells", n_cells)] {
        if n > MAX_COUNT {
            return Err(err(path, format!("<Piece> {name} = {n} is over the limit of {MAX_COUNT}")));
        }
    }
    // Appended arrays end where the next one starts (base64 runs are decoded up to there).
    let mut offsets: Vec<usize> = doc
        .descendants()
        .filter(|n| n.has_tag_name("DataArray") && n.attribute("format") == Some("appended"))
        .filter_map(|n| n.attribute("offset").and_then(|o| o.trim().parse().ok()))
        .collect();
    offsets.sort_unstable();
    let mut arrays = Vec::new();
    // The grid's field data (VTK's `TimeValue`: the data set's time), then the piece's sections.
    let field_data =
        piece.parent().into_iter().flat_map(|g| g.children()).filter(|n| n.has_tag_name("FieldData"));
    for section in field_data.chain(piece.children().filter(|n| n.is_element())) {
        for node in section.children().filter(|n| n.has_tag_name("DataArray")) {
            let section_name = section.tag_name().name();
            let name = node.attribute("Name").unwrap_or(if section_name == "Points" { "Points" } else { "" });
            // Of the field data only the time is read (other entries may be strings).
            if section_name == "FieldData" && name != TIME_VALUE {
                continue;
            }
            let ty = node.attribute("type").unwrap_or("Float32");
            let comps: usize = node.attribute("NumberOfComponents").and_then(|c| c.parse().ok()).unwrap_or(1);
            let what = |d: String| err(path, format!("array {name}: {d}"));
            // The most bytes this array can hold, from the piece's counts (field data: its own
            // declared tuples, checked against the same limit).
            let tuples = match (section_name, name) {
                ("FieldData", _) => {
                    let n: usize = node
                        .attribute("NumberOfTuples")
                        .and_then(|v| v.trim().parse().ok())
                        .ok_or_else(|| what("field data without a valid NumberOfTuples".into()))?;
                    if n > MAX_COUNT {
                        return Err(what(format!("NumberOfTuples = {n} is over the limit of {MAX_COUNT}")));
                    }
                    n
                }
                ("Points" | "PointData", _) => n_points,
                ("CellData", _) | ("Cells", "offsets" | "types" | "faceoffsets") => n_cells,
                _ => n_cells.saturating_mul(MAX_NODES_PER_CELL),
            };
            let limit = tuples.saturating_mul(comps).saturating_mul(type_size(ty).unwrap_or(8));
            let values = match node.attribute("format").unwrap_or("ascii") {
                "ascii" => node
                    .text()
                    .unwrap_or("")
                    .split_ascii_whitespace()
                    .map(|w| w.parse::<f64>().map_err(|_| what(format!("{w:?} is not a number"))))
                    .collect::<Result<Vec<f64>, _>>()?,
                "binary" => {
                    let raw = base64_runs(node.text().unwrap_or("").as_bytes()).map_err(what)?;
                    let (data, _) = framing.block(&raw, limit).map_err(what)?;
                    numbers(ty, &data).map_err(what)?
                }
                "appended" => {
                    let (base64, start) = appended
                        .ok_or_else(|| what("appended, but the file has no <AppendedData>".into()))?;
                    let offset: usize = node
                        .attribute("offset")
                        .and_then(|o| o.trim().parse().ok())
                        .ok_or_else(|| what("appended without an offset".into()))?;
                    let rest = bytes
                        .get(start.saturating_add(offset)..)
                        .ok_or_else(|| what("offset past the end of the file".into()))?;
                    let data = if base64 {
                        // This array's base64 runs: up to the next array's offset, or to the
                        // end of the appended text.
                        let next = offsets.iter().find(|&&o| o > offset).map_or(rest.len(), |&o| o - offset);
                        let text = &rest[..next.min(rest.len())];
                        let end = text.iter().position(|&c| c == b'<').unwrap_or(text.len());
                        let raw = base64_runs(&text[..end]).map_err(what)?;
                        framing.block(&raw, limit).map_err(what)?.0
                    } else {
                        framing.block(rest, limit).map_err(what)?.0
                    };
                    numbers(ty, &data).map_err(what)?
                }
                other => return Err(what(format!("format {other:?} is not supported"))),
            };
            arrays.push(DataArray {
                section: section_name.to_string(),
                name: name.to_string(),
                components: comps,
                values,
            });
        }
    }
    Ok(UnstructuredGrid { path: path.to_path_buf(), points: n_points, cells: n_cells, arrays, version })
}

/// The field-data array in which VTK writers put a data set's time (ParaView reads it as the
/// time of the file).
pub const TIME_VALUE: &str = "TimeValue";

impl UnstructuredGrid {
    /// The data set's time from its field data's `TimeValue`, if it has exactly one finite
    /// value there.
    pub fn time_value(&self) -> Option<f64> {
        match self.array("FieldData", TIME_VALUE).map(|a| a.values.as_slice()) {
            Some([t]) if t.is_finite() => Some(*t),
            _ => None,
        }
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    memchr::memmem::find(haystack, needle)
}
