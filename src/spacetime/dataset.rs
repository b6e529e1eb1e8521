//! Spacetime data sets as files and by name: loading a `.gst` (memory-mapped) or `.vtu`
//! (read, sorted by lowest time), generating the named data sets — `pulses` (structured) and
//! the seed's tent-pitched scenarios `crack`, `inclusions`, `booster` — in memory or streamed
//! to disk, and converting between the two formats. The fields are analytic, L2-projected
//! per element: not solved.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::scenario::{self, Scenario};
use super::{generate, gst, vtu, ElementRecord, SpacetimeData, SpacetimeError};

/// The most elements a data set built in memory may have (a `.vtu`, a generated render):
/// about 7 GB of mesh and records at this count.
pub const MAX_IN_MEMORY: usize = 50_000_000;

/// The generated tetrahedral data sets by name, as [`generated`] and [`generate_file`] know
/// them (the command line's `--generate` values).
pub const DATA_SETS: [&str; 4] = ["pulses", "crack", "inclusions", "booster"];
/// What `spacetime render|view --generate` accepts: [`DATA_SETS`] and `bar1d` (seed 003's
/// Fig. 3, a 1D bar over (x, t) triangles, drawn as one image).
pub const RENDERABLE: [&str; 5] = ["pulses", "crack", "inclusions", "booster", "bar1d"];

fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase()
}

/// A spacetime data file's format by its extension: `"gst"` or `"vtu"`, if it is one.
pub fn format_of(path: &Path) -> Option<&'static str> {
    match extension(path).as_str() {
        "gst" => Some("gst"),
        "vtu" => Some("vtu"),
        _ => None,
    }
}

fn request(detail: String) -> SpacetimeError {
    SpacetimeError::Request(detail)
}

/// Loads a `.gst` (mapped) or `.vtu` (read, sorted by lowest time).
pub fn load(path: &Path) -> Result<SpacetimeData, SpacetimeError> {
    match extension(path).as_str() {
        "gst" => gst::open(path),
        "vtu" => {
            let mut mesh = vtu::read(path)?;
            mesh.sort_by_lowest_time();
            SpacetimeData::from_mesh(&mesh).map_err(|e| SpacetimeError::File {
                path: path.to_path_buf(),
                detail: format!("{e} (element numbers after sorting by lowest time)"),
            })
        }
        _ => Err(SpacetimeError::File {
            path: path.to_path_buf(),
            detail: "unknown extension: expected .gst or .vtu".into(),
        }),
    }
}

/// The data set `name` of about `elements` elements, generated in memory.
pub fn generated(name: &str, elements: usize) -> Result<SpacetimeData, SpacetimeError> {
    check_count(elements)?;
    if elements > MAX_IN_MEMORY {
        return Err(request(format!(
            "{elements} elements: a generated data set is built in memory, at most {MAX_IN_MEMORY}; \
             generate a .gst with `galerkin spacetime gen` and render that"
        )));
    }
    let mesh = match name {
        "pulses" => generate::pulses(elements),
        other => scenario::generate(parse_scenario(other)?, elements),
    };
    SpacetimeData::from_mesh(&mesh)
}

fn parse_scenario(name: &str) -> Result<Scenario, SpacetimeError> {
    if name == "bar1d" {
        return Err(request(
            "bar1d is a 1D bar over (x, t) triangles, not a tetrahedral data set: render it with \
             `galerkin spacetime render --generate bar1d`"
                .into(),
        ));
    }
    name.parse::<Scenario>()
        .map_err(|_| request(format!("unknown data set {name:?} (available: {})", DATA_SETS.join(", "))))
}

fn check_count(elements: usize) -> Result<(), SpacetimeError> {
    if elements == 0 {
        return Err(request("the element count must be positive".into()));
    }
    Ok(())
}

/// A data set written by [`generate_file`] or [`convert`].
#[derive(Clone, Debug)]
pub struct Written {
    /// Elements written.
    pub elements: usize,
    /// The file's size, bytes.
    pub bytes: u64,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl Written {
    fn of(path: &Path, elements: usize, start: Instant) -> Self {
        let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        Self { elements, bytes, seconds: start.elapsed().as_secs_f64() }
    }
}

/// Generates the data set `name` of about `elements` elements into `out`: a `.gst` is streamed
/// (memory stays bounded at any size; `progress` is told the elements done), a `.vtu` is
/// built in memory (at most [`MAX_IN_MEMORY`] elements). Nothing is left at `out` on failure.
pub fn generate_file(
    name: &str,
    elements: usize,
    out: &Path,
    progress: &mut dyn FnMut(u64),
) -> Result<Written, SpacetimeError> {
    check_count(elements)?;
    let start = Instant::now();
    let ext = extension(out);
    if ext == "vtu" && elements > MAX_IN_MEMORY {
        return Err(request(format!(
            "{elements} elements: a .vtu is built in memory, at most {MAX_IN_MEMORY} elements; write a .gst (streamed) instead"
        )));
    }
    if ext != "gst" && ext != "vtu" {
        return Err(SpacetimeError::File {
            path: out.to_path_buf(),
            detail: format!("unknown extension {ext:?}: expected .gst or .vtu"),
        });
    }
    let scenario = if name == "pulses" { None } else { Some(parse_scenario(name)?) };
    match (scenario, ext.as_str()) {
        (None, "gst") => {
            let mut writer = gst::GstWriter::create(out, &[generate::PULSES_MATERIAL])?;
            generate::stream_pulses(elements, &mut |r| writer.push(r), progress)?;
            let n = writer.len();
            writer.finish()?;
            Ok(Written::of(out, n, start))
        }
        (Some(scenario), "gst") => {
            let mut writer = gst::GstWriter::create(out, &scenario::materials(scenario))?;
            let mut failed: Option<SpacetimeError> = None;
            scenario::generate_streaming(scenario, elements, &mut |g| {
                if failed.is_none() {
                    let r = ElementRecord::new(g.corners, &g.frame, g.material, &g.coefficients);
                    failed = writer.push(&r).err();
                    if writer.len() % 4096 == 0 {
                        progress(writer.len() as u64);
                    }
                }
            });
            if let Some(e) = failed {
                return Err(e);
            }
            let n = writer.len();
            writer.finish()?;
            Ok(Written::of(out, n, start))
        }
        (scenario, _) => {
            let mesh = match scenario {
                None => generate::pulses(elements),
                Some(s) => scenario::generate(s, elements),
            };
            vtu::write(out, &mesh)?;
            Ok(Written::of(out, mesh.tets.len(), start))
        }
    }
}

/// Converts `input` (`.gst` or `.vtu`) to `output` (`.gst` or `.vtu`).
pub fn convert(input: &Path, output: &Path) -> Result<Written, SpacetimeError> {
    let start = Instant::now();
    let data = load(input)?;
    match extension(output).as_str() {
        "gst" => {
            gst::write(output, &data)?;
        }
        "vtu" => vtu::write(output, &data.to_mesh())?,
        other => {
            return Err(SpacetimeError::File {
                path: output.to_path_buf(),
                detail: format!("unknown extension {other:?}: expected .gst or .vtu"),
            })
        }
    }
    Ok(Written::of(output, data.len(), start))
}

/// The data set `name` of `elements` elements kept as `DIR/NAME-ELEMENTS.gst` between runs
/// (benchmarks): generated on first use, reused while it opens.
pub fn cached(
    dir: &Path,
    name: &str,
    elements: usize,
    progress: &mut dyn FnMut(u64),
) -> Result<PathBuf, SpacetimeError> {
    std::fs::create_dir_all(dir).map_err(|e| SpacetimeError::File {
        path: dir.to_path_buf(),
        detail: format!("creating the folder: {e}"),
    })?;
    let path = dir.join(format!("{name}-{elements}.gst"));
    if gst::open(&path).is_err() {
        generate_file(name, elements, &path, progress)?;
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_and_extensions_are_refused_before_any_work() {
        let dir = tempfile::tempdir().expect("temp dir");
        let e = generate_file("tornado", 1000, &dir.path().join("a.gst"), &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("tornado") && e.to_string().contains(&DATA_SETS.join(", ")), "{e}");
        let e = generate_file("pulses", 1000, &dir.path().join("a.txt"), &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("a.txt"), "{e}");
        let e = generate_file("pulses", 0, &dir.path().join("a.gst"), &mut |_| {}).unwrap_err();
        assert!(e.to_string().contains("positive"), "{e}");
        let refused =
            |name: &str, n: usize| generated(name, n).err().map(|e| e.to_string()).unwrap_or_default();
        assert!(refused("bar1d", 1000).contains("1D bar"));
        assert!(refused("pulses", MAX_IN_MEMORY + 1).contains("in memory"));
        assert_eq!(std::fs::read_dir(dir.path()).map(|d| d.count()).unwrap_or(0), 0);
    }

    #[test]
    fn generated_files_load_as_the_data_set_in_memory_and_convert_both_ways() {
        let dir = tempfile::tempdir().expect("temp dir");
        let gst_path = dir.path().join("p.gst");
        let written = generate_file("pulses", 2000, &gst_path, &mut |_| {}).expect("gst");
        let in_memory = generated("pulses", 2000).expect("in memory");
        assert_eq!(written.elements, in_memory.len());
        assert!(written.bytes > 0);
        let vtu_path = dir.path().join("p.vtu");
        assert_eq!(convert(&gst_path, &vtu_path).expect("to vtu").elements, in_memory.len());
        let back = load(&vtu_path).expect("read back");
        assert_eq!(back.len(), in_memory.len());
        assert_eq!(back.summary().time, in_memory.summary().time);
    }
}
