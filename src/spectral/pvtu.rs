//! Partitioned VTK data sets (`.pvtu`): a `<VTKFile type="PUnstructuredGrid">` listing its
//! pieces (`<Piece Source="F_0.vtu"/>`), each a `.vtu` of some of the cells, as
//! `vtkXMLPUnstructuredGridWriter` and parallel solvers write them. The pieces are read with
//! [`super::vtu`] and joined into one data set, in the order listed: their cells one after
//! another, each piece's fields by name (every piece must have the same fields, with the same
//! steps, cells of one shape and order). Points shared between pieces are each piece's own —
//! every element keeps its own nodes here anyway. Empty pieces are skipped.

use std::path::Path;

use super::error::SpectralError;
use super::mesh::SpectralMesh;
use super::vtu;

/// The most pieces a `.pvtu` may list (each is a file read in turn).
pub const MAX_PIECES: usize = 100_000;

/// Reads the partitioned data set at `path` (see the module docs). Refused, naming the file:
/// not a `PUnstructuredGrid`, no piece or more than [`MAX_PIECES`], every piece empty, a piece
/// missing or unreadable (naming the piece), pieces of other shapes, orders or fields than the
/// first's (naming the piece and what differs).
pub fn read(path: &Path) -> Result<SpectralMesh, SpectralError> {
    let bad = |detail: String| SpectralError::File { path: path.to_path_buf(), detail };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let sources = pieces(&text).map_err(bad)?;
    let base = path.parent().unwrap_or(Path::new(""));
    let mut joined: Option<SpectralMesh> = None;
    for source in &sources {
        let piece_path = base.join(source);
        let Some(piece) = vtu::read_piece(&piece_path)? else { continue };
        let in_piece = |detail: String| SpectralError::File { path: piece_path.clone(), detail };
        joined = Some(match joined {
            None => piece,
            Some(first) => join(first, piece).map_err(in_piece)?,
        });
    }
    joined.ok_or_else(|| bad(format!("all {} pieces are empty", sources.len())))
}

/// The `Source` of every `<Piece>` of a `.pvtu`'s text, in order.
fn pieces(text: &str) -> Result<Vec<String>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("PUnstructuredGrid") {
        return Err("not a partitioned unstructured grid (<VTKFile type=\"PUnstructuredGrid\">)".into());
    }
    let mut sources = Vec::new();
    for (k, node) in doc.descendants().filter(|n| n.has_tag_name("Piece")).enumerate() {
        if k >= MAX_PIECES {
            return Err(format!("more than {MAX_PIECES} pieces"));
        }
        let source = node.attribute("Source").ok_or_else(|| format!("piece {k} has no Source"))?;
        sources.push(source.to_string());
    }
    if sources.is_empty() {
        return Err("it lists no piece".into());
    }
    Ok(sources)
}

/// A `.pvtu` ([`read`]) or, by any other extension, a `.vtu` ([`vtu::read`]): one data set as
/// a single file or in pieces (what `spectral::load` and a collection's entries read).
pub fn read_vtu_or_pieces(path: &Path) -> Result<SpectralMesh, SpectralError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("pvtu") => read(path),
        _ => vtu::read(path),
    }
}

/// `first` with `piece`'s elements after its own; the message says what differs.
fn join(mut first: SpectralMesh, piece: SpectralMesh) -> Result<SpectralMesh, String> {
    if piece.shape != first.shape {
        return Err(format!("its cells are {:?}, the first piece's {:?}", piece.shape, first.shape));
    }
    if piece.basis != first.basis || piece.geometry != first.geometry {
        return Err(format!(
            "order {} on {} nodes (geometry {}), the first piece's {} on {} (geometry {})",
            piece.basis.order,
            piece.basis.set.name(),
            piece.geometry.order,
            first.basis.order,
            first.basis.set.name(),
            first.geometry.order
        ));
    }
    let names = |m: &SpectralMesh| m.fields.iter().map(|f| f.name.clone()).collect::<Vec<_>>();
    if names(&piece) != names(&first) {
        return Err(format!("fields {:?}, the first piece's {:?}", names(&piece), names(&first)));
    }
    for (f, p) in first.fields.iter_mut().zip(piece.fields) {
        if p.times != f.times {
            return Err(format!(
                "field {:?} at times {:?}, the first piece's at {:?}",
                f.name, p.times, f.times
            ));
        }
        for (steps, more) in f.steps.iter_mut().zip(p.steps) {
            steps.extend(more);
        }
    }
    let (first_nodes, piece_nodes) = (first.points.len(), piece.points.len());
    first.points.extend(piece.points);
    // Rational pieces beside polynomial ones: the latter's weights are 1.
    let weights = match (first.weights.take(), piece.weights) {
        (None, None) => None,
        (a, b) => {
            let mut w = a.unwrap_or_else(|| vec![1.0; first_nodes]);
            w.extend(b.unwrap_or_else(|| vec![1.0; piece_nodes]));
            Some(w)
        }
    };
    let mesh = SpectralMesh::new(first.shape, first.geometry, first.basis, first.points, first.fields)
        .map_err(|e| e.to_string())?;
    match weights {
        Some(w) => mesh.with_weights(w).map_err(|e| e.to_string()),
        None => Ok(mesh),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_are_listed_in_order_and_bad_files_are_refused() {
        let text = r#"<VTKFile type="PUnstructuredGrid"><PUnstructuredGrid><Piece Source="a_0.vtu"/><Piece Source="a_1.vtu"/></PUnstructuredGrid></VTKFile>"#;
        assert_eq!(pieces(text).unwrap(), ["a_0.vtu", "a_1.vtu"]);
        assert!(pieces(r#"<VTKFile type="UnstructuredGrid"/>"#).unwrap_err().contains("PUnstructuredGrid"));
        assert!(pieces(r#"<VTKFile type="PUnstructuredGrid"/>"#).unwrap_err().contains("no piece"));
        let no_source = r#"<VTKFile type="PUnstructuredGrid"><Piece/></VTKFile>"#;
        assert!(pieces(no_source).unwrap_err().contains("piece 0 has no Source"));
    }
}
