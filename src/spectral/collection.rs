//! ParaView's time series: a `.pvd` (a VTK `Collection`: `<DataSet timestep="t"
//! file="F.vtu"/>` entries) or a `.vtu.series` (ParaView's JSON file series: `{"file-series-
//! version": "1.0", "files": [{"name": "F.vtu", "time": t}, …]}`), each file a `.vtu` of the
//! same cells ([`super::vtu`]); their fields become the time steps of one data set, at the
//! series' times, in time order. This is how ParaView writes an animated data set (File ▸
//! Save Data with all time steps) and how solvers that write VTK hand ParaView a run.

use std::path::Path;

use super::error::SpectralError;
use super::mesh::SpectralMesh;
use super::pvtu::read_vtu_or_pieces;

/// The most data sets a collection may list (each is a file read in turn).
pub const MAX_DATASETS: usize = 100_000;

/// Reads the collection at `path` (see the module docs). Refused, naming the file: no data
/// set, more than [`MAX_DATASETS`], several parts at one time, a listed file that is missing or
/// unreadable, cells that differ from the first file's (naming the element), a field missing
/// from a file, a file that itself holds several time steps.
pub fn read_collection(path: &Path) -> Result<SpectralMesh, SpectralError> {
    let bad = |detail: String| SpectralError::File { path: path.to_path_buf(), detail };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let sets = if path.to_string_lossy().to_ascii_lowercase().ends_with(".series") {
        series_entries(&text).map_err(bad)?
    } else {
        pvd_entries(&text).map_err(bad)?
    };
    read_entries(path, sets)
}

/// The `(time, part, file)` entries of a `.pvd`'s text.
fn pvd_entries(text: &str) -> Result<Vec<(f64, String, String)>, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("XML: {e}"))?;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("Collection") {
        return Err("not a VTK collection (<VTKFile type=\"Collection\">)".into());
    }
    let mut sets = Vec::new();
    // Lines counted on from the previous entry (entries come in document order): linear in the
    // file, where `text_pos_at` would count from the start for each entry.
    let (mut counted_to, mut line) = (0, 1);
    for (k, node) in doc.descendants().filter(|n| n.has_tag_name("DataSet")).enumerate() {
        if k >= MAX_DATASETS {
            return Err(format!("more than {MAX_DATASETS} data sets"));
        }
        let start = node.range().start.max(counted_to);
        line += text.as_bytes()[counted_to..start].iter().filter(|&&b| b == b'\n').count();
        counted_to = start;
        let time: f64 = node
            .attribute("timestep")
            .unwrap_or("0")
            .trim()
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| {
                format!("line {line}: timestep {:?} is not a number", node.attribute("timestep"))
            })?;
        let file = node.attribute("file").ok_or_else(|| format!("line {line}: a DataSet without a file"))?;
        sets.push((time, node.attribute("part").unwrap_or("0").to_string(), file.to_string()));
    }
    Ok(sets)
}

/// The `(time, part, file)` entries of a `.vtu.series`' JSON text.
fn series_entries(text: &str) -> Result<Vec<(f64, String, String)>, String> {
    #[derive(serde::Deserialize)]
    struct Entry {
        name: String,
        time: f64,
    }
    #[derive(serde::Deserialize)]
    struct Series {
        #[serde(rename = "file-series-version")]
        version: String,
        files: Vec<Entry>,
    }
    let series: Series = serde_json::from_str(text).map_err(|e| format!("JSON file series: {e}"))?;
    if series.version != "1.0" {
        return Err(format!("file-series-version {:?} (1.0 is read)", series.version));
    }
    if series.files.len() > MAX_DATASETS {
        return Err(format!("more than {MAX_DATASETS} files"));
    }
    series
        .files
        .into_iter()
        .enumerate()
        .map(|(k, e)| {
            if e.time.is_finite() {
                Ok((e.time, "0".to_string(), e.name))
            } else {
                Err(format!("files[{k}]: time {} is not finite", e.time))
            }
        })
        .collect()
}

/// Reads the entries' files (see [`read_collection`]).
fn read_entries(path: &Path, mut sets: Vec<(f64, String, String)>) -> Result<SpectralMesh, SpectralError> {
    let bad = |detail: String| SpectralError::File { path: path.to_path_buf(), detail };
    if sets.is_empty() {
        return Err(bad("the series lists no data set".into()));
    }
    sets.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let Some(w) = sets.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(bad(format!(
            "two data sets at time {} (parts {:?} and {:?}): multi-part collections are not read",
            w[0].0, w[0].1, w[1].1
        )));
    }
    let base = path.parent().unwrap_or(Path::new(""));
    let mut mesh: Option<SpectralMesh> = None;
    let mut times = Vec::with_capacity(sets.len());
    for (time, _, file) in &sets {
        let step_path = base.join(file);
        let step = read_vtu_or_pieces(&step_path)?;
        let step_file = |detail: String| SpectralError::File { path: step_path.clone(), detail };
        if let Some(f) = step.fields.iter().find(|f| f.steps.len() != 1) {
            return Err(step_file(format!(
                "field {:?} has {} time steps in one file of a collection (one each)",
                f.name,
                f.steps.len()
            )));
        }
        match &mut mesh {
            None => mesh = Some(step),
            Some(first) => {
                same_cells(first, &step).map_err(step_file)?;
                for field in &mut first.fields {
                    let values = step.fields.iter().find(|f| f.name == field.name).ok_or_else(|| {
                        step_file(format!("no field {:?} (the first file has it)", field.name))
                    })?;
                    field.steps.push(values.steps[0].clone());
                }
            }
        }
        times.push(*time);
    }
    let mut mesh = mesh.ok_or_else(|| bad("no data set read".into()))?;
    for field in &mut mesh.fields {
        field.times = times.clone();
    }
    Ok(mesh)
}

/// Whether `b` has the cells of `a`: shape, orders and every control point (to 1e-12 of the
/// data set's extent, what writing doubles as text can move).
fn same_cells(a: &SpectralMesh, b: &SpectralMesh) -> Result<(), String> {
    if a.shape != b.shape || a.elements() != b.elements() || a.basis.order != b.basis.order {
        return Err(format!(
            "{} {:?} elements of order {}, the first file has {} of order {}",
            b.elements(),
            b.shape,
            b.basis.order,
            a.elements(),
            a.basis.order
        ));
    }
    let (lo, hi) = a.bounds();
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let per = a.points_per_element();
    for (i, (p, q)) in a.points.iter().zip(&b.points).enumerate() {
        if (0..3).any(|k| (p[k] - q[k]).abs() > 1e-12 * extent) {
            return Err(format!("element {}: its points differ from the first file's", i / per));
        }
    }
    // Rational cells: the weights are part of the geometry (and of every field's basis).
    match (&a.weights, &b.weights) {
        (None, None) => {}
        (Some(wa), Some(wb)) => {
            if let Some(i) = wa.iter().zip(wb).position(|(x, y)| (x - y).abs() > 1e-12 * x.abs()) {
                return Err(format!(
                    "element {}: its rational weights differ from the first file's",
                    i / per
                ));
            }
        }
        _ => return Err("rational cells in one file, polynomial ones in the other".into()),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Files of one series must agree on rational weights as on points: VTK's polynomial and
    /// rational Bézier fixtures share their control points and differ only in the weights.
    #[test]
    fn a_series_refuses_files_whose_rational_weights_differ() {
        let fixture = |name: &str| {
            let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
            crate::spectral::vtu::read(&path).expect("fixture")
        };
        let (plain, rational) = (fixture("bezier_quad.vtu"), fixture("bezier_quad_rational.vtu"));
        assert_eq!(same_cells(&rational, &rational.clone()), Ok(()));
        let e = same_cells(&plain, &rational).expect_err("polynomial against rational");
        assert!(e.contains("rational cells in one file"), "{e}");
        let mut other = rational.clone();
        if let Some(w) = other.weights.as_mut() {
            w[20] *= 1.5;
        }
        let e = same_cells(&rational, &other).expect_err("other weights");
        assert!(e.contains("element 1") && e.contains("rational weights differ"), "{e}");
    }

    /// A collection's entries are read in time linear in their count (issue 49: the line of
    /// each entry was counted from the file's start, 40,000 entries took 5 s), one over the cap
    /// is refused, and a bad entry's line is still right.
    #[test]
    fn collection_entries_are_linear_capped_and_name_their_line() {
        let pvd = |n: usize, bad: Option<usize>| {
            let mut text =
                String::from("<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\">\n<Collection>\n");
            for k in 0..n {
                let t = if bad == Some(k) { "x".to_string() } else { k.to_string() };
                text.push_str(&format!("<DataSet timestep=\"{t}\" file=\"s{k}.vtu\"/>\n"));
            }
            text + "</Collection>\n</VTKFile>\n"
        };
        let start = std::time::Instant::now();
        let sets = pvd_entries(&pvd(MAX_DATASETS, None)).expect("at the cap");
        assert_eq!(sets.len(), MAX_DATASETS);
        let e = pvd_entries(&pvd(2 * MAX_DATASETS, None)).expect_err("twice the cap");
        assert!(e.contains(&format!("more than {MAX_DATASETS}")), "{e}");
        // Quadratic counting took minutes here; linear takes well under a second in release.
        assert!(start.elapsed() < std::time::Duration::from_secs(20), "{:?}", start.elapsed());
        let e = pvd_entries(&pvd(60_000, Some(50_000))).expect_err("a bad timestep");
        assert!(e.starts_with("line 50004:"), "{e}");
    }
}
