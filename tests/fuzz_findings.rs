//! What fuzzing found (`make fuzz`, fuzz/fuzz_targets), kept as regression tests in the ordinary
//! suite: each input that crashed a loader, reduced to the edit of a valid file that causes it,
//! must now be refused with an error naming the file and the place.

use std::path::{Path, PathBuf};

fn fixture(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Target `mfem` (artifact crash-9fed28c7…): a hexahedron listing one vertex twice
/// (`1 5 3 4 7 7 …`) reached the DOF numbering of its faces, whose edge search panicked ("an
/// edge of the face"). Elements with a repeated vertex are now refused where they are read.
#[test]
fn an_mfem_element_with_a_repeated_vertex_is_refused_naming_line_and_element() {
    let dir = tempfile::Builder::new().prefix("galerkin-fuzz-finding-").tempdir().expect("scratch");
    let text = std::fs::read_to_string(fixture("tests/data/mfem/hex_h1_p3.mesh")).expect("MFEM's hexahedra");
    let degenerate = text.replacen("1 5 3 4 7 6 12 13 16 15", "1 5 3 4 7 7 12 13 16 15", 1);
    assert_ne!(degenerate, text, "the fixture has the element");
    let mesh = dir.path().join("degenerate.mesh");
    std::fs::write(&mesh, degenerate).expect("written");
    let e = galerkin::spectral::load(&mesh, &[fixture("tests/data/mfem/hex_h1_p3.gf")])
        .expect_err("a degenerate element")
        .to_string();
    assert!(
        e.contains("degenerate.mesh") && e.contains("element 1") && e.contains("vertex 7 appears twice"),
        "{e}"
    );
    let line = text.lines().position(|l| l == "1 5 3 4 7 6 12 13 16 15").expect("the line") + 1;
    assert!(e.contains(&format!("line {line}:")), "{e} (line {line})");
}
