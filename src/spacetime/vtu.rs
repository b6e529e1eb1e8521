//! VTK XML unstructured grids (`.vtu`) of spacetime data, for interoperability: points are
//! `(x, y, t)`, cells are `VTK_TETRA` (10), and cell data hold each element's field —
//! `coefficients` (40 components: the 2-vectors `c_α` of the cubic, x then y, in the monomial
//! order of [`super::MONOMIALS`]), `frame` (6: centre x, y, t, extents x, y, t), `material`
//! (Int32 index) and `lambda`, `mu`, `density` (the material's values per cell, so ParaView
//! users see them).
//!
//! Writing uses appended raw binary (`header_type="UInt64"`). Reading accepts what VTK and
//! ParaView write: `ascii`, inline `binary` (base64) and `appended` data (raw or base64), with
//! UInt32 or UInt64 block headers, uncompressed or zlib-compressed (`vtkZLibDataCompressor`).
//! Optional on reading: `frame` (default: each element's bounding box, the generator's
//! frame), `material` (default: one material per distinct (λ, μ, ρ)) and `density` (default 1).
//! Every error names the file and, for data errors, the array or element.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use super::cubic::{LocalFrame, Material};
use super::error::SpacetimeError;
use super::mesh::{ElementField, SpacetimeMesh};

/// `VTK_TETRA`.
const VTK_TETRA: u8 = 10;

fn err(path: &Path, detail: impl Into<String>) -> SpacetimeError {
    SpacetimeError::File { path: path.to_path_buf(), detail: detail.into() }
}

/// Writes `mesh` to `path` (written as `path.partial`, renamed when complete).
pub fn write(path: &Path, mesh: &SpacetimeMesh) -> Result<(), SpacetimeError> {
    let n_cells = mesh.tets.len();
    let mut arrays: Vec<(&str, &str, usize, Vec<u8>)> = Vec::new();
    let f64s = |v: &mut dyn Iterator<Item = f64>| v.flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    arrays.push(("Points", "Float64", 3, f64s(&mut mesh.vertices.iter().flatten().copied())));
    let conn: Vec<u8> = mesh.tets.iter().flatten().flat_map(|&i| i64::from(i).to_le_bytes()).collect();
    arrays.push(("connectivity", "Int64", 1, conn));
    arrays.push(("offsets", "Int64", 1, (1..=n_cells as i64).flat_map(|k| (4 * k).to_le_bytes()).collect()));
    arrays.push(("types", "UInt8", 1, vec![VTK_TETRA; n_cells]));
    let fields = &mesh.fields;
    arrays.push((
        "coefficients",
        "Float64",
        40,
        f64s(&mut fields.iter().flat_map(|f| f.coefficients).flatten()),
    ));
    arrays.push((
        "frame",
        "Float64",
        6,
        f64s(&mut fields.iter().flat_map(|f| f.frame.centre.into_iter().chain(f.frame.extent))),
    ));
    arrays.push((
        "material",
        "Int32",
        1,
        fields.iter().flat_map(|f| (f.material as i32).to_le_bytes()).collect(),
    ));
    let mat = |f: &ElementField| mesh.materials.get(f.material as usize).copied();
    for (name, get) in [
        ("lambda", (|m: Material| m.lambda) as fn(Material) -> f64),
        ("mu", |m: Material| m.mu),
        ("density", |m: Material| m.density),
    ] {
        arrays.push((name, "Float64", 1, f64s(&mut fields.iter().map(|f| mat(f).map_or(f64::NAN, get)))));
    }
    let mut offset = 0u64;
    let mut xml = String::new();
    let mut tag = |name: &str, ty: &str, comps: usize, bytes: usize| {
        let s = format!(
            "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"appended\" offset=\"{offset}\"/>\n"
        );
        offset += 8 + bytes as u64;
        s
    };
    xml.push_str("<?xml version=\"1.0\"?>\n<!-- galerkin spacetime DG data (seed 003): points are (x, y, t); cell data hold each element's cubic displacement. -->\n");
    xml.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    xml.push_str(&format!(
        "  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{n_cells}\">\n      <Points>\n",
        mesh.vertices.len()
    ));
    xml.push_str(&tag(arrays[0].0, arrays[0].1, arrays[0].2, arrays[0].3.len()));
    xml.push_str("      </Points>\n      <Cells>\n");
    for a in &arrays[1..4] {
        xml.push_str(&tag(a.0, a.1, a.2, a.3.len()));
    }
    xml.push_str("      </Cells>\n      <CellData>\n");
    for a in &arrays[4..] {
        xml.push_str(&tag(a.0, a.1, a.2, a.3.len()));
    }
    xml.push_str(
        "      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _",
    );
    let mut partial = path.as_os_str().to_owned();
    partial.push(".partial");
    let partial = std::path::PathBuf::from(partial);
    let result = (|| -> std::io::Result<()> {
        let mut out = std::io::BufWriter::new(std::fs::File::create(&partial)?);
        out.write_all(xml.as_bytes())?;
        for a in &arrays {
            out.write_all(&(a.3.len() as u64).to_le_bytes())?;
            out.write_all(&a.3)?;
        }
        out.write_all(b"\n  </AppendedData>\n</VTKFile>\n")?;
        out.flush()
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&partial);
        return Err(err(&partial, e.to_string()));
    }
    std::fs::rename(&partial, path).map_err(|e| err(path, e.to_string()))
}

/// How the binary blocks of a file are framed.
struct Framing {
    header_u64: bool,
    zlib: bool,
}

fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in text.bytes().filter(|c| !c.is_ascii_whitespace()) {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            b'=' => continue,
            _ => return None,
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

impl Framing {
    fn header_bytes(&self) -> usize {
        if self.header_u64 {
            8
        } else {
            4
        }
    }

    fn word(&self, b: &[u8], k: usize) -> Option<usize> {
        let h = self.header_bytes();
        let w = b.get(k * h..(k + 1) * h)?;
        Some(if self.header_u64 {
            u64::from_le_bytes(w.try_into().ok()?) as usize
        } else {
            u32::from_le_bytes(w.try_into().ok()?) as usize
        })
    }

    /// Decodes one block (its header and data) from `b`; returns the data and the bytes used.
    fn block(&self, b: &[u8]) -> Result<(Vec<u8>, usize), String> {
        let h = self.header_bytes();
        if !self.zlib {
            let n = self.word(b, 0).ok_or("truncated block header")?;
            let data =
                b.get(h..h + n).ok_or_else(|| format!("truncated: a block of {n} bytes is cut short"))?;
            return Ok((data.to_vec(), h + n));
        }
        // [blocks, block size, last block size, compressed sizes…], then the zlib streams.
        let blocks = self.word(b, 0).ok_or("truncated compression header")?;
        let mut at = h * (3 + blocks);
        if b.len() < at {
            return Err("truncated compression header".into());
        }
        let mut out = Vec::new();
        for k in 0..blocks {
            let size = self.word(b, 3 + k).ok_or("truncated compression header")?;
            let z = b.get(at..at + size).ok_or("truncated compressed block")?;
            let d = miniz_oxide::inflate::decompress_to_vec_zlib(z)
                .map_err(|e| format!("bad zlib data: {e:?}"))?;
            out.extend_from_slice(&d);
            at += size;
        }
        Ok((out, at))
    }
}

/// Numbers of a DataArray of VTK type `ty` from little-endian bytes.
fn numbers(ty: &str, b: &[u8]) -> Result<Vec<f64>, String> {
    macro_rules! conv {
        ($t:ty) => {{
            const N: usize = std::mem::size_of::<$t>();
            if !b.len().is_multiple_of(N) {
                return Err(format!("{} bytes is not a whole number of {ty} values", b.len()));
            }
            b.chunks_exact(N).map(|c| <$t>::from_le_bytes(c.try_into().expect("N bytes")) as f64).collect()
        }};
    }
    Ok(match ty {
        "Float64" => conv!(f64),
        "Float32" => conv!(f32),
        "Int64" => conv!(i64),
        "UInt64" => conv!(u64),
        "Int32" => conv!(i32),
        "UInt32" => conv!(u32),
        "Int16" => conv!(i16),
        "UInt16" => conv!(u16),
        "Int8" => conv!(i8),
        "UInt8" => conv!(u8),
        other => return Err(format!("unsupported type {other}")),
    })
}

/// Reads a spacetime mesh from a `.vtu` file (see the module docs for what is accepted).
/// The mesh is validated; elements keep the file's order.
pub fn read(path: &Path) -> Result<SpacetimeMesh, SpacetimeError> {
    let bytes = std::fs::read(path).map_err(|e| err(path, e.to_string()))?;
    // Appended raw data are not XML: parse the text before them, closed.
    let appended_at = find(&bytes, b"<AppendedData");
    let text_end = appended_at.unwrap_or(bytes.len());
    let mut text = std::str::from_utf8(&bytes[..text_end])
        .map_err(|e| err(path, format!("not UTF-8 XML text at byte {}", e.valid_up_to())))?
        .to_string();
    if appended_at.is_some() {
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
        zlib: match root.attribute("compressor") {
            None | Some("") => false,
            Some("vtkZLibDataCompressor") => true,
            Some(other) => return Err(err(path, format!("compressor {other} is not supported (only zlib)"))),
        },
    };
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
    let count = |name: &str| -> Result<usize, SpacetimeError> {
        piece
            .attribute(name)
            .and_then(|v| v.trim().parse().ok())
            .ok_or_else(|| err(path, format!("<Piece> lacks a valid {name}")))
    };
    let (n_points, n_cells) = (count("NumberOfPoints")?, count("NumberOfCells")?);
    let array = |section: &str, name: &str| -> Result<Option<(Vec<f64>, usize)>, SpacetimeError> {
        let Some(node) =
            piece.children().filter(|n| n.has_tag_name(section)).flat_map(|s| s.children()).find(|n| {
                n.has_tag_name("DataArray") && (n.attribute("Name") == Some(name) || section == "Points")
            })
        else {
            return Ok(None);
        };
        let ty = node.attribute("type").unwrap_or("Float32");
        let comps: usize = node.attribute("NumberOfComponents").and_then(|c| c.parse().ok()).unwrap_or(1);
        let what = |d: String| err(path, format!("array {name}: {d}"));
        let values = match node.attribute("format").unwrap_or("ascii") {
            "ascii" => node
                .text()
                .unwrap_or("")
                .split_ascii_whitespace()
                .map(|w| w.parse::<f64>().map_err(|_| what(format!("{w:?} is not a number"))))
                .collect::<Result<Vec<f64>, _>>()?,
            "binary" => {
                let raw =
                    base64_decode(node.text().unwrap_or("")).ok_or_else(|| what("bad base64".into()))?;
                let (data, _) = framing.block(&raw).map_err(what)?;
                numbers(ty, &data).map_err(what)?
            }
            "appended" => {
                let (base64, start) =
                    appended.ok_or_else(|| what("appended, but the file has no <AppendedData>".into()))?;
                let offset: usize = node
                    .attribute("offset")
                    .and_then(|o| o.trim().parse().ok())
                    .ok_or_else(|| what("appended without an offset".into()))?;
                let data = if base64 {
                    // Each array is its own base64 run, up to the next array's offset.
                    let rest = &bytes[start + offset..];
                    let end =
                        rest.iter().position(|&c| c == b'<' || c.is_ascii_whitespace()).unwrap_or(rest.len());
                    let raw = base64_decode(&String::from_utf8_lossy(&rest[..end]))
                        .ok_or_else(|| what("bad base64".into()))?;
                    framing.block(&raw).map_err(what)?.0
                } else {
                    let rest = bytes
                        .get(start + offset..)
                        .ok_or_else(|| what("offset past the end of the file".into()))?;
                    framing.block(rest).map_err(what)?.0
                };
                numbers(ty, &data).map_err(what)?
            }
            other => return Err(what(format!("format {other:?} is not supported"))),
        };
        Ok(Some((values, comps)))
    };
    let need = |section: &str, name: &str, comps: usize, n: usize| -> Result<Vec<f64>, SpacetimeError> {
        let (v, c) =
            array(section, name)?.ok_or_else(|| err(path, format!("no {section} array {name:?}")))?;
        if c != comps || v.len() != comps * n {
            return Err(err(
                path,
                format!("array {name}: {} values in {c} components, expected {n} × {comps}", v.len()),
            ));
        }
        Ok(v)
    };
    let optional = |name: &str, comps: usize| -> Result<Option<Vec<f64>>, SpacetimeError> {
        match array("CellData", name)? {
            None => Ok(None),
            Some(_) => need("CellData", name, comps, n_cells).map(Some),
        }
    };
    let points = need("Points", "Points", 3, n_points)?;
    let conn = need("Cells", "connectivity", 1, 4 * n_cells)?;
    let offsets = need("Cells", "offsets", 1, n_cells)?;
    let types = need("Cells", "types", 1, n_cells)?;
    let coefficients = need("CellData", "coefficients", 40, n_cells)?;
    let lambda = need("CellData", "lambda", 1, n_cells)?;
    let mu = need("CellData", "mu", 1, n_cells)?;
    let density = optional("density", 1)?;
    let frame = optional("frame", 6)?;
    let material = optional("material", 1)?;

    let mut mesh = SpacetimeMesh {
        vertices: points.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        ..Default::default()
    };
    let mut materials: HashMap<u32, Material> = HashMap::new();
    let mut by_value: HashMap<[u64; 3], u32> = HashMap::new();
    for e in 0..n_cells {
        let cell = |d: String| err(path, format!("element {e}: {d}"));
        if types[e] != f64::from(VTK_TETRA) {
            return Err(cell(format!("cell type {} (only VTK_TETRA = 10 is a spacetime element)", types[e])));
        }
        if offsets[e] != (4 * (e + 1)) as f64 {
            return Err(cell(format!("offset {} (tetrahedra need 4 × (element + 1))", offsets[e])));
        }
        let mut tet = [0u32; 4];
        for (k, t) in tet.iter_mut().enumerate() {
            let i = conn[4 * e + k];
            if !(i >= 0.0 && i < n_points as f64 && i.fract() == 0.0) {
                return Err(cell(format!("vertex index {i} is out of range ({n_points} points)")));
            }
            *t = i as u32;
        }
        mesh.tets.push(tet);
        let m = Material { lambda: lambda[e], mu: mu[e], density: density.as_ref().map_or(1.0, |d| d[e]) };
        let index = match &material {
            Some(ids) => {
                let id = ids[e];
                if !(id >= 0.0 && id.fract() == 0.0 && id < 65536.0) {
                    return Err(cell(format!("material index {id} is not a small non-negative integer")));
                }
                let id = id as u32;
                let known = *materials.entry(id).or_insert(m);
                if known != m && !(known.lambda.is_nan() || m.lambda.is_nan()) {
                    return Err(cell(format!("material {id} is {m:?} here but {known:?} elsewhere")));
                }
                id
            }
            None => {
                let key = [m.lambda.to_bits(), m.mu.to_bits(), m.density.to_bits()];
                let next = by_value.len() as u32;
                let id = *by_value.entry(key).or_insert(next);
                materials.insert(id, m);
                id
            }
        };
        let corners = tet.map(|i| mesh.vertices[i as usize]);
        let frame = match &frame {
            Some(f) => {
                let f = &f[6 * e..6 * e + 6];
                LocalFrame { centre: [f[0], f[1], f[2]], extent: [f[3], f[4], f[5]] }
            }
            None => LocalFrame::bounding(&corners),
        };
        let c = &coefficients[40 * e..40 * e + 40];
        mesh.fields.push(ElementField {
            frame,
            material: index,
            coefficients: std::array::from_fn(|a| [c[2 * a], c[2 * a + 1]]),
        });
    }
    let n_materials = materials.keys().max().map_or(0, |&m| m as usize + 1);
    mesh.materials = (0..n_materials)
        // An index no element uses gets a copy of one that is used (it is never read).
        .map(|i| {
            materials
                .get(&(i as u32))
                .or_else(|| materials.values().next())
                .copied()
                .expect("n_materials > 0")
        })
        .collect();
    mesh.validate().map_err(|e| err(path, e.to_string()))?;
    Ok(mesh)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_the_rfc_4648_vectors() {
        for (text, plain) in
            [("", ""), ("Zg==", "f"), ("Zm8=", "fo"), ("Zm9v", "foo"), ("Zm9vYmFy", "foobar")]
        {
            assert_eq!(base64_decode(text).unwrap(), plain.as_bytes());
        }
        assert!(base64_decode("Zm9v!").is_none());
    }
}
