//! Wavefront OBJ files, read one way for every capability that takes them (a fluid's surface
//! animation, a signed-distance obstacle, a radiosity scene): the `tobj` crate parses them
//! (triangulated, one index per corner), and this module checks what it cannot say — every
//! vertex line's coordinates are numbers, finite and within [`crate::limits::MAX_MAGNITUDE`],
//! every face's vertex indices exist — naming the line, so an error reads
//! `line 12: face vertex 9 does not exist (the file has 8 vertices)` instead of tobj's
//! `face vertex index out of bounds`. Materials (`mtllib`) are not read.

use std::io::BufReader;
use std::path::Path;

/// The most lines an OBJ file may have (each is looked at once).
pub const MAX_LINES: usize = 1 << 31;

/// Reads the OBJ file at `path`: its objects, triangulated. The error is a sentence naming the
/// line where it can (the caller adds the file).
pub fn load(path: &Path) -> Result<Vec<tobj::Model>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read it: {e}"))?;
    parse(&text)
}

/// [`load`] of OBJ `text`.
pub fn parse(text: &str) -> Result<Vec<tobj::Model>, String> {
    check_lines(text)?;
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ..Default::default() };
    let (models, _) = tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| format!("{e} (the line could not be found)"))?;
    if models.is_empty() {
        return Err("no objects (no faces)".into());
    }
    Ok(models)
}

/// The checks [`load`] makes before tobj parses: vertex coordinates and face indices, by line.
fn check_lines(text: &str) -> Result<(), String> {
    let vertices = text.lines().filter(|l| l.split_whitespace().next() == Some("v")).count();
    let mut seen = 0usize;
    for (k, line) in text.lines().enumerate() {
        let at = k + 1;
        if k >= MAX_LINES {
            return Err(format!("more than {MAX_LINES} lines"));
        }
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                seen += 1;
                let coords: Vec<&str> = words.collect();
                if coords.len() < 3 {
                    return Err(format!("line {at}: vertex {seen} has {} coordinates, not 3", coords.len()));
                }
                for c in &coords[..3] {
                    let x: f64 = c
                        .parse()
                        .map_err(|_| format!("line {at}: vertex {seen}: coordinate {c:?} is not a number"))?;
                    if crate::limits::first_out_of_range(&[x]).is_some() {
                        return Err(format!(
                            "line {at}: vertex {seen}: coordinate {}",
                            crate::limits::out_of_range_reason(x)
                        ));
                    }
                }
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                if corners.len() < 3 {
                    return Err(format!("line {at}: a face of {} vertices (at least 3)", corners.len()));
                }
                for c in corners {
                    let index = c.split('/').next().unwrap_or_default();
                    let i: i64 = index
                        .parse()
                        .map_err(|_| format!("line {at}: face vertex {c:?} is not a vertex number"))?;
                    // OBJ indices count from 1; negative ones count back from the last vertex
                    // so far.
                    let resolved = if i < 0 { seen as i64 + 1 + i } else { i };
                    if !(1..=vertices as i64).contains(&resolved) {
                        return Err(format!(
                            "line {at}: face vertex {i} does not exist (the file has {vertices} vertices)"
                        ));
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRIANGLE: &str = "o t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

    #[test]
    fn errors_name_the_line() {
        assert_eq!(parse(TRIANGLE).expect("valid").len(), 1);
        let cases = [
            (
                TRIANGLE.replace("f 1 2 3", "f 1 2 9"),
                "line 5: face vertex 9 does not exist (the file has 3 vertices)",
            ),
            (TRIANGLE.replace("v 1 0 0", "v 1 x 0"), "line 3: vertex 2: coordinate \"x\" is not a number"),
            (
                TRIANGLE.replace("v 1 0 0", "v 1 1e308 0"),
                "line 3: vertex 2: coordinate 1e308 (past the limit",
            ),
            (TRIANGLE.replace("v 1 0 0", "v 1 nan 0"), "line 3: vertex 2: coordinate NaN (not finite)"),
            (TRIANGLE.replace("v 1 0 0", "v 1 0"), "line 3: vertex 2 has 2 coordinates, not 3"),
            (TRIANGLE.replace("f 1 2 3", "f 1 2"), "line 5: a face of 2 vertices"),
            (TRIANGLE.replace("f 1 2 3", "f 1 -4 3"), "line 5: face vertex -4 does not exist"),
        ];
        for (text, want) in cases {
            let e = parse(&text).expect_err(want);
            assert!(e.starts_with(want), "{e:?} is not {want:?}");
        }
        // Relative indices and texture/normal indices are fine.
        assert!(parse(&TRIANGLE.replace("f 1 2 3", "f -3 -2 -1")).is_ok());
    }
}
