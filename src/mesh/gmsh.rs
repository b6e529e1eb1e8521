//! Gmsh MSH 4.1 input, ASCII and binary: a user's own triangle (2D) or tetrahedral (3D) mesh.
//!
//! Read: `$MeshFormat` (version 4.1, file type, data size 8), `$Nodes` (entity blocks of node
//! tags then coordinates; parametric coordinates skipped), `$Elements` (entity blocks of one
//! element type: 4-node tetrahedra, type 4, or 3-node triangles, type 2). Every other section
//! (`$Entities`, `$PhysicalNames`, `$Periodic`, …) is skipped to its `$End…` line. If the file
//! has tetrahedra the mesh is 3D and triangles (boundary facets) are ignored; otherwise its
//! triangles make a 2D mesh, which must lie in the plane z = 0. Nodes no element uses are
//! dropped. Periodic node pairs are not taken from `$Periodic`: the fluid's topology re-matches
//! the two sides of a periodic axis geometrically ([`super::Topology::new`]).
//!
//! Errors name the file and the line (ASCII) or byte offset (binary), and the element or node.

use std::collections::HashMap;
use std::path::Path;

use super::{MeshError, SimplexMesh};

fn err(path: &Path, at: String, message: impl std::fmt::Display) -> MeshError {
    MeshError::Generation(format!("{}: {at}: {message}", path.display()))
}

/// A reader over the file's bytes, ASCII tokens or binary values.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    binary: bool,
    path: &'a Path,
}

impl<'a> Reader<'a> {
    fn at(&self) -> String {
        if self.binary {
            format!("byte {}", self.pos)
        } else {
            format!(
                "line {}",
                self.bytes[..self.pos.min(self.bytes.len())].iter().filter(|&&b| b == b'\n').count() + 1
            )
        }
    }

    fn fail(&self, message: impl std::fmt::Display) -> MeshError {
        err(self.path, self.at(), message)
    }

    fn skip_space(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next whitespace-separated ASCII token.
    fn token(&mut self) -> Result<&'a str, MeshError> {
        self.skip_space();
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.fail("unexpected end of file"));
        }
        std::str::from_utf8(&self.bytes[start..self.pos]).map_err(|_| self.fail("not text"))
    }

    fn line(&mut self) -> Result<&'a str, MeshError> {
        self.skip_space();
        let start = self.pos;
        while self.pos < self.bytes.len() && self.bytes[self.pos] != b'\n' {
            self.pos += 1;
        }
        let s = std::str::from_utf8(&self.bytes[start..self.pos]).map_err(|_| self.fail("not text"))?;
        // Consume the newline: binary data starts right after it.
        self.pos = (self.pos + 1).min(self.bytes.len());
        Ok(s.trim_end())
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], MeshError> {
        if self.pos + n > self.bytes.len() {
            return Err(self.fail("unexpected end of file"));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn int(&mut self) -> Result<i64, MeshError> {
        if self.binary {
            Ok(i64::from(i32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes"))))
        } else {
            let t = self.token()?;
            t.parse().map_err(|_| self.fail(format!("expected an integer, found {t:?}")))
        }
    }

    fn size(&mut self) -> Result<u64, MeshError> {
        if self.binary {
            Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
        } else {
            let t = self.token()?;
            t.parse().map_err(|_| self.fail(format!("expected a non-negative integer, found {t:?}")))
        }
    }

    fn double(&mut self) -> Result<f64, MeshError> {
        let v = if self.binary {
            f64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes"))
        } else {
            let t = self.token()?;
            t.parse().map_err(|_| self.fail(format!("expected a number, found {t:?}")))?
        };
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.fail("coordinate is not finite"))
        }
    }

    /// Skips to just after the line `$End<name>`.
    fn skip_section(&mut self, name: &str) -> Result<(), MeshError> {
        let marker = format!("$End{name}");
        let hay = &self.bytes[self.pos..];
        match memchr::memmem::find(hay, marker.as_bytes()) {
            Some(i) => {
                self.pos += i + marker.len();
                Ok(())
            }
            None => Err(self.fail(format!("section ${name} has no {marker}"))),
        }
    }

    /// A `$Nodes`/`$Elements` header: the number of entity blocks (then the total count and
    /// the tag range, not needed).
    fn blocks(&mut self) -> Result<u64, MeshError> {
        // Each block header holds four numbers: at least 8 bytes.
        let blocks = self.count("the entity block count", 8)? as u64;
        for _ in 0..3 {
            self.size()?;
        }
        Ok(blocks)
    }

    /// A count the file declares, checked against the limit and the bytes left
    /// ([`crate::limits::declared_count`]) before anything is allocated from it.
    fn count(&mut self, what: &str, min_bytes: usize) -> Result<usize, MeshError> {
        let n = self.size()?;
        let remaining = self.bytes.len().saturating_sub(self.pos);
        crate::limits::declared_count(what, n, remaining, min_bytes).map_err(|e| self.fail(e))
    }

    fn expect_end(&mut self, name: &str) -> Result<(), MeshError> {
        let l = self.line()?;
        if l == format!("$End{name}") {
            Ok(())
        } else {
            Err(self.fail(format!("expected $End{name}, found {l:?}")))
        }
    }
}

/// Reads a Gmsh MSH 4.1 file (ASCII or binary).
pub fn read_msh(path: &Path) -> Result<SimplexMesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|e| err(path, "open".into(), e))?;
    parse_msh(&bytes, path)
}

/// Parses MSH 4.1 `bytes` (`path` names it in errors).
pub fn parse_msh(bytes: &[u8], path: &Path) -> Result<SimplexMesh, MeshError> {
    let mut r = Reader { bytes, pos: 0, binary: false, path };
    let mut nodes: HashMap<u64, [f64; 3]> = HashMap::new();
    let mut tets: Vec<([u64; 4], u64)> = Vec::new();
    let mut tris: Vec<([u64; 3], u64)> = Vec::new();
    let mut seen_format = false;
    loop {
        r.skip_space();
        if r.pos >= bytes.len() {
            break;
        }
        let header = r.line()?;
        let Some(name) = header.strip_prefix('$') else {
            return Err(r.fail(format!("expected a section header, found {header:?}")));
        };
        match name {
            "MeshFormat" => {
                r.binary = false;
                let version = r.token()?;
                if version != "4.1" {
                    return Err(
                        r.fail(format!("MSH version {version}: only 4.1 is read (Gmsh: -format msh41)"))
                    );
                }
                let file_type = r.int()?;
                let data_size = r.int()?;
                if data_size != 8 {
                    return Err(r.fail(format!("data size {data_size}: only 8 is read")));
                }
                if file_type == 1 {
                    // The newline, then the integer 1 in the file's byte order.
                    while r.pos < bytes.len() && bytes[r.pos] != b'\n' {
                        r.pos += 1;
                    }
                    r.pos += 1;
                    let one = i32::from_le_bytes(r.take(4)?.try_into().expect("4 bytes"));
                    if one != 1 {
                        return Err(r.fail("a big-endian binary file: only little-endian is read"));
                    }
                    r.binary = true;
                }
                r.expect_end("MeshFormat")?;
                seen_format = true;
            }
            "Nodes" if seen_format => {
                let blocks = r.blocks()?;
                for _ in 0..blocks {
                    let _dim = r.int()?;
                    let _tag = r.int()?;
                    let parametric = r.int()?;
                    // Each node takes at least a tag and three coordinates: 8 bytes in text
                    // ("1\n0 0 0\n"), 32 in binary.
                    let n = r.count("a node block's node count", if r.binary { 32 } else { 8 })?;
                    let mut tags = crate::limits::vec_for(n, "a node block's tags").map_err(|e| r.fail(e))?;
                    for _ in 0..n {
                        tags.push(r.size()?);
                    }
                    for tag in tags {
                        let p = [r.double()?, r.double()?, r.double()?];
                        if parametric != 0 {
                            return Err(
                                r.fail("parametric node coordinates are not read (save without them)")
                            );
                        }
                        nodes.insert(tag, p);
                    }
                }
                r.expect_end("Nodes")?;
            }
            "Elements" if seen_format => {
                let blocks = r.blocks()?;
                for _ in 0..blocks {
                    let _dim = r.int()?;
                    let _entity = r.int()?;
                    let kind = r.int()?;
                    // Each element takes at least a tag and one node: 4 bytes in text, 16 in binary.
                    let n = r.count("an element block's element count", if r.binary { 16 } else { 4 })?;
                    let per = match kind {
                        2 => 3,
                        4 => 4,
                        15 => 1,
                        1 => 2,
                        3 => 4,
                        5 => 8,
                        6 => 6,
                        7 => 5,
                        other => {
                            return Err(r.fail(format!("element type {other}: only linear elements are read")))
                        }
                    };
                    for _ in 0..n {
                        let tag = r.size()?;
                        let mut v = [0u64; 8];
                        for slot in v.iter_mut().take(per) {
                            *slot = r.size()?;
                        }
                        match kind {
                            4 => tets.push(([v[0], v[1], v[2], v[3]], tag)),
                            2 => tris.push(([v[0], v[1], v[2]], tag)),
                            _ => {}
                        }
                    }
                }
                r.expect_end("Elements")?;
            }
            "Nodes" | "Elements" => return Err(r.fail("$MeshFormat must come first")),
            other => r.skip_section(other)?,
        }
    }
    if !seen_format {
        return Err(err(path, "line 1".into(), "no $MeshFormat: not a Gmsh MSH file"));
    }
    let dim = if tets.is_empty() { 2 } else { 3 };
    let mut index: HashMap<u64, u32> = HashMap::new();
    let mut g = Vec::new();
    let mut cells = Vec::new();
    let mut add = |tag: u64, element: u64| -> Result<u32, MeshError> {
        if let Some(&i) = index.get(&tag) {
            return Ok(i);
        }
        let p = nodes
            .get(&tag)
            .ok_or_else(|| err(path, format!("element {element}"), format!("node {tag} is not in $Nodes")))?;
        if dim == 2 && p[2].abs() > 0.0 {
            return Err(err(path, format!("node {tag}"), "a 2D (triangle) mesh must lie in the plane z = 0"));
        }
        let i = index.len() as u32;
        index.insert(tag, i);
        g.extend_from_slice(&p[..dim]);
        Ok(i)
    };
    if dim == 3 {
        for (t, tag) in &tets {
            for &v in t {
                cells.push(add(v, *tag)?);
            }
        }
    } else {
        for (t, tag) in &tris {
            for &v in t {
                cells.push(add(v, *tag)?);
            }
        }
    }
    if cells.is_empty() {
        return Err(err(path, "$Elements".into(), "no triangles or tetrahedra"));
    }
    SimplexMesh::new(dim, g, cells).map_err(|e| err(path, "mesh".into(), e))
}

/// Writes `mesh` as MSH 4.1 (ASCII or binary), one entity holding every node and element:
/// for tests and for handing meshes to Gmsh-reading tools.
pub fn write_msh(mesh: &SimplexMesh, binary: bool) -> Vec<u8> {
    let d = mesh.dim();
    let (nv, nc) = (mesh.vertex_count(), mesh.cell_count());
    let mut out = Vec::new();
    out.extend_from_slice(format!("$MeshFormat\n4.1 {} 8\n", u8::from(binary)).as_bytes());
    if binary {
        out.extend_from_slice(&1i32.to_le_bytes());
        out.push(b'\n');
    }
    out.extend_from_slice(b"$EndMeshFormat\n$Nodes\n");
    let size = |out: &mut Vec<u8>, v: u64, last: bool| {
        if binary {
            out.extend_from_slice(&v.to_le_bytes());
        } else {
            out.extend_from_slice(format!("{v}{}", if last { "\n" } else { " " }).as_bytes());
        }
    };
    let int = |out: &mut Vec<u8>, v: i32, last: bool| {
        if binary {
            out.extend_from_slice(&v.to_le_bytes());
        } else {
            out.extend_from_slice(format!("{v}{}", if last { "\n" } else { " " }).as_bytes());
        }
    };
    for (i, v) in [1u64, nv as u64, 1, nv as u64].into_iter().enumerate() {
        size(&mut out, v, i == 3);
    }
    int(&mut out, d as i32, false);
    int(&mut out, 1, false);
    int(&mut out, 0, false);
    size(&mut out, nv as u64, true);
    for v in 0..nv {
        size(&mut out, v as u64 + 1, true);
    }
    for v in 0..nv {
        let p = mesh.point(v);
        for (k, x) in p.iter().enumerate() {
            if binary {
                out.extend_from_slice(&x.to_le_bytes());
            } else {
                out.extend_from_slice(format!("{x:.17e}{}", if k == 2 { "\n" } else { " " }).as_bytes());
            }
        }
    }
    out.extend_from_slice(b"$EndNodes\n$Elements\n");
    for (i, v) in [1u64, nc as u64, 1, nc as u64].into_iter().enumerate() {
        size(&mut out, v, i == 3);
    }
    int(&mut out, d as i32, false);
    int(&mut out, 1, false);
    int(&mut out, if d == 3 { 4 } else { 2 }, false);
    size(&mut out, nc as u64, true);
    for c in 0..nc {
        size(&mut out, c as u64 + 1, false);
        let cell = mesh.cell(c);
        for (k, &v) in cell.iter().enumerate() {
            size(&mut out, u64::from(v) + 1, k == d);
        }
    }
    out.extend_from_slice(b"$EndElements\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::kuhn::kuhn_box;

    #[test]
    fn msh_files_round_trip_ascii_and_binary_and_bad_ones_name_the_place() {
        for dim in [2, 3] {
            let m = kuhn_box(dim, [3, 2, 2], [1.5, 1.0, 1.0]).expect("box");
            for binary in [false, true] {
                let bytes = write_msh(&m, binary);
                let back = parse_msh(&bytes, Path::new("box.msh")).expect("parses");
                assert_eq!(back.dim(), dim);
                // Vertices are numbered in order of first use; the cells' corners are the same.
                assert_eq!(back.cell_count(), m.cell_count());
                for c in 0..m.cell_count() {
                    assert_eq!(back.cell_points(c), m.cell_points(c), "{dim}D cell {c}");
                }
            }
        }
        // A hand-written ASCII file with an $Entities section, unused nodes and boundary
        // triangles beside the tetrahedra.
        let text =
            "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n\
$Nodes\n1 5 1 5\n3 1 0 5\n10\n20\n30\n40\n50\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n9 9 9\n$EndNodes\n\
$Elements\n2 2 1 2\n2 1 2 1\n7 10 20 30\n3 1 4 1\n8 10 20 30 40\n$EndElements\n";
        let m = parse_msh(text.as_bytes(), Path::new("hand.msh")).expect("parses");
        assert_eq!((m.dim(), m.vertex_count(), m.cell_count()), (3, 4, 1));
        let bad = text.replace("8 10 20 30 40", "8 10 20 30 99");
        let e = parse_msh(bad.as_bytes(), Path::new("bad.msh")).expect_err("missing node").to_string();
        assert!(e.contains("bad.msh") && e.contains("element 8") && e.contains("node 99"), "{e}");
        let bad = text.replace("4.1 0 8", "2.2 0 8");
        let e = parse_msh(bad.as_bytes(), Path::new("old.msh")).expect_err("old version").to_string();
        assert!(e.contains("old.msh: line 2") && e.contains("4.1"), "{e}");
        let bad = text.replace("0 0 1\n9 9 9", "0 0 1e999\n9 9 9");
        assert!(parse_msh(bad.as_bytes(), Path::new("nan.msh")).is_err());
        // A flat tetrahedron is refused naming the cell.
        let bad = text.replace("0 0 1\n9 9 9", "0.5 0.5 0\n9 9 9");
        let e = parse_msh(bad.as_bytes(), Path::new("flat.msh")).expect_err("flat").to_string();
        assert!(e.contains("cell 0"), "{e}");
    }
}
