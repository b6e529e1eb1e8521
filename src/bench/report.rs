//! BENCHMARKS.md as a generated reference (issue 50): `galerkin bench all --out FILE` runs every
//! benchmark command, captures the Markdown each prints, and writes it between two marker lines
//! of FILE under one provenance line — commit, date, device and driver, CPU, the command and
//! how long it ran — so the document's tables are exactly what the named commit printed on the
//! named machine, and the prose around the markers is left as it was.
//!
//! This module does the text work (provenance, heading levels, splicing); the command line runs
//! the benchmarks and writes the file (atomically, through [`crate::atomic_file`]).

use std::fmt::Write as _;
use std::path::Path;

/// The line that opens the generated part of a document.
pub const BEGIN_MARKER: &str = "<!-- begin: galerkin bench all -->";
/// The line that closes the generated part of a document.
pub const END_MARKER: &str = "<!-- end: galerkin bench all -->";

/// Where and when figures were measured: the line every generated table sits under.
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    /// Short hash of the commit the binary was run from, with `+dirty` when the work tree had
    /// uncommitted changes; `unknown` outside a git work tree.
    pub commit: String,
    /// The UTC date of the run, `YYYY-MM-DD`.
    pub date: String,
    /// The Vulkan device's name (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub device: String,
    /// The Vulkan driver's name and version.
    pub driver: String,
    /// The CPU's model name (from `/proc/cpuinfo`) and its logical core count.
    pub cpu: String,
}

impl Provenance {
    /// Reads the commit (`git`, run in `repo`), today's UTC date and the CPU; `device` and
    /// `driver` come from the opened device.
    pub fn read(repo: &Path, device: &str, driver: &str) -> Self {
        let days = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| (d.as_secs() / 86_400) as i64)
            .unwrap_or(0);
        let (y, m, d) = civil_from_days(days);
        Self {
            commit: git_commit(repo),
            date: format!("{y:04}-{m:02}-{d:02}"),
            device: device.to_string(),
            driver: driver.to_string(),
            cpu: cpu_model(),
        }
    }

    /// The provenance line: `Measured: commit `abc1234`, 2026-12-06, device — driver, CPU,
    /// `galerkin bench all` (812 s).` The form tests/benchmarks_doc.rs looks for.
    pub fn line(&self, command: &str, seconds: f64) -> String {
        format!(
            "Measured: commit `{}`, {}, {} — {}, {}, `{}` ({:.0} s).",
            self.commit, self.date, self.device, self.driver, self.cpu, command, seconds
        )
    }
}

/// One benchmark command's captured output.
#[derive(Clone, Debug)]
pub struct Captured {
    /// The command line after `galerkin` (e.g. `spectral bench`).
    pub command: String,
    /// What it printed on stdout (Markdown).
    pub stdout: String,
    /// Wall time of the command, seconds.
    pub seconds: f64,
}

/// The generated part of the document: the markers, one provenance line for the whole run, and
/// each command's output under a `###` heading naming the command and its time, its own
/// headings demoted below that.
pub fn generated_section(provenance: &Provenance, all_command: &str, runs: &[Captured]) -> String {
    let total: f64 = runs.iter().map(|r| r.seconds).sum();
    let mut s = String::new();
    let _ = writeln!(s, "{BEGIN_MARKER}");
    let _ = writeln!(
        s,
        "<!-- written by `galerkin {all_command} --out`: edit the commands, not these lines -->\n"
    );
    let _ = writeln!(s, "{}\n", provenance.line(&format!("galerkin {all_command}"), total));
    for run in runs {
        let _ = writeln!(s, "### `galerkin {}` ({:.0} s)\n", run.command, run.seconds);
        let body = demote_headings(run.stdout.trim(), 4);
        let _ = writeln!(s, "{body}\n");
    }
    let _ = writeln!(s, "{END_MARKER}");
    s
}

/// `doc` with the part between [`BEGIN_MARKER`] and [`END_MARKER`] (markers included) replaced
/// by `generated` (which carries its own markers). An error names `file` when either marker is
/// missing, repeated or out of order: nothing is guessed.
pub fn splice(doc: &str, generated: &str, file: &Path) -> Result<String, String> {
    let find_line = |marker: &str| -> Result<usize, String> {
        let hits: Vec<usize> = doc.match_indices(marker).map(|(i, _)| i).collect();
        match hits.as_slice() {
            [i] => Ok(*i),
            [] => Err(format!(
                "{}: no line `{marker}`; the generated tables go between `{BEGIN_MARKER}` and `{END_MARKER}` (add both lines where they belong)",
                file.display()
            )),
            _ => Err(format!("{}: `{marker}` appears {} times; it must appear once", file.display(), hits.len())),
        }
    };
    let begin = find_line(BEGIN_MARKER)?;
    let end = find_line(END_MARKER)?;
    if end < begin {
        return Err(format!("{}: `{END_MARKER}` comes before `{BEGIN_MARKER}`", file.display()));
    }
    let after = end + END_MARKER.len();
    let after = after + doc[after..].find('\n').map_or(doc.len() - after, |n| n + 1);
    let mut out = String::with_capacity(doc.len() + generated.len());
    out.push_str(&doc[..begin]);
    out.push_str(generated);
    out.push_str(&doc[after..]);
    Ok(out)
}

/// A new document holding only the generated part, for `--out` naming a file that does not
/// exist yet.
pub fn new_document(generated: &str) -> String {
    format!("# Benchmarks\n\n{generated}")
}

/// Markdown headings outside code fences pushed down so that the shallowest is at level
/// `min_level` (a command's `## Table` under the run's `###` heading becomes `####`).
pub fn demote_headings(md: &str, min_level: usize) -> String {
    let level = |line: &str| {
        let n = line.bytes().take_while(|&b| b == b'#').count();
        (n > 0 && line[n..].starts_with(' ')).then_some(n)
    };
    let mut fenced = false;
    let mut shallowest = usize::MAX;
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced {
            if let Some(n) = level(line) {
                shallowest = shallowest.min(n);
            }
        }
    }
    let shift = min_level.saturating_sub(shallowest.min(min_level));
    let mut fenced = false;
    let mut out = String::with_capacity(md.len() + 64);
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && level(line).is_some() {
            out.extend(std::iter::repeat_n('#', shift));
        }
        out.push_str(line);
        out.push('\n');
    }
    out.truncate(out.trim_end_matches('\n').len());
    out
}

/// Runs `exe args…` as a child process (stderr passed through, so its progress lines show),
/// echoing each line of its stdout to ours as it comes and capturing it. Fails, naming the
/// command, when it cannot start or exits unsuccessfully.
pub fn run_captured(exe: &Path, args: &[String], command: &str) -> Result<Captured, String> {
    use std::io::{BufRead, Write};
    let start = std::time::Instant::now();
    let mut child = std::process::Command::new(exe)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .map_err(|e| format!("`galerkin {command}`: cannot start {}: {e}", exe.display()))?;
    let mut stdout = String::new();
    if let Some(pipe) = child.stdout.take() {
        let mut echo = std::io::stdout().lock();
        for line in std::io::BufReader::new(pipe).lines() {
            let line = line.map_err(|e| format!("`galerkin {command}`: reading its output: {e}"))?;
            let _ = writeln!(echo, "{line}");
            stdout.push_str(&line);
            stdout.push('\n');
        }
    }
    let status = child.wait().map_err(|e| format!("`galerkin {command}`: {e}"))?;
    if !status.success() {
        return Err(format!("`galerkin {command}` failed ({status}); nothing was written"));
    }
    Ok(Captured { command: command.to_string(), stdout, seconds: start.elapsed().as_secs_f64() })
}

/// The short hash of HEAD in `repo`, `+dirty` when tracked files differ from it; `unknown`
/// when git or the repository is not there.
fn git_commit(repo: &Path) -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(repo)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short=7", "HEAD"]) {
        Some(hash) if !hash.is_empty() => {
            let dirty =
                git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
            if dirty {
                format!("{hash}+dirty")
            } else {
                hash
            }
        }
        _ => "unknown".to_string(),
    }
}

/// `model name` from `/proc/cpuinfo` and the number of logical cores this process may use.
fn cpu_model() -> String {
    let name = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.split_whitespace().collect::<Vec<_>>().join(" "))
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{name} ({cores} cores)")
}

/// The proleptic Gregorian date (year, month, day) of a day count since 1970-01-01: Howard
/// Hinnant's `civil_from_days` ("chrono-Compatible Low-Level Date Algorithms").
pub fn civil_from_days(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let y = yoe + era * 400 + i64::from(m <= 2);
    (y, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates_match_known_days() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(-1), (1969, 12, 31));
        // 2000-02-29 (a leap day of a century divisible by 400) is day 11,016.
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(11_017), (2000, 3, 1));
        // 2026-12-06 is day 20,793.
        assert_eq!(civil_from_days(20_793), (2026, 12, 6));
    }

    #[test]
    fn headings_are_demoted_outside_fences_only() {
        let md = "## Table\n\ntext\n\n```sh\n# a shell comment\n```\n### Sub\n#hashtag";
        let out = demote_headings(md, 4);
        assert_eq!(out, "#### Table\n\ntext\n\n```sh\n# a shell comment\n```\n##### Sub\n#hashtag");
        // Already deep enough: unchanged.
        assert_eq!(demote_headings("#### A\n##### B", 4), "#### A\n##### B");
    }

    #[test]
    fn splice_replaces_between_markers_and_keeps_the_rest() {
        let doc = format!("# Title\n\nprose\n\n{BEGIN_MARKER}\nold\n{END_MARKER}\n\nmore prose\n");
        let generated = format!("{BEGIN_MARKER}\nnew\n{END_MARKER}\n");
        let out = splice(&doc, &generated, Path::new("B.md")).expect("markers present");
        assert_eq!(out, format!("# Title\n\nprose\n\n{BEGIN_MARKER}\nnew\n{END_MARKER}\n\nmore prose\n"));
        // Splicing twice is the same as once.
        assert_eq!(splice(&out, &generated, Path::new("B.md")).expect("markers present"), out);
    }

    #[test]
    fn splice_refuses_missing_repeated_or_swapped_markers_naming_the_file() {
        let gen = format!("{BEGIN_MARKER}\n{END_MARKER}\n");
        let e = splice("no markers", &gen, Path::new("docs/B.md")).unwrap_err();
        assert!(e.contains("docs/B.md") && e.contains(BEGIN_MARKER), "{e}");
        let twice = format!("{BEGIN_MARKER}\n{BEGIN_MARKER}\n{END_MARKER}\n");
        assert!(splice(&twice, &gen, Path::new("B.md")).unwrap_err().contains("2 times"));
        let swapped = format!("{END_MARKER}\n{BEGIN_MARKER}\n");
        assert!(splice(&swapped, &gen, Path::new("B.md")).unwrap_err().contains("before"));
    }

    #[test]
    fn the_provenance_line_names_commit_date_device_and_command() {
        let p = Provenance {
            commit: "abc1234".into(),
            date: "2026-12-06".into(),
            device: "llvmpipe".into(),
            driver: "Mesa 25.0.7".into(),
            cpu: "Xeon (2 cores)".into(),
        };
        let line = p.line("galerkin bench all", 812.4);
        assert_eq!(line, "Measured: commit `abc1234`, 2026-12-06, llvmpipe — Mesa 25.0.7, Xeon (2 cores), `galerkin bench all` (812 s).");
        let section = generated_section(
            &p,
            "bench all",
            &[Captured {
                command: "bench gpu".into(),
                stdout: "## Ceilings\n| a |\n|---|\n| 1 |\n".into(),
                seconds: 3.0,
            }],
        );
        assert!(section.starts_with(BEGIN_MARKER) && section.trim_end().ends_with(END_MARKER));
        assert!(section.contains("### `galerkin bench gpu` (3 s)\n\n#### Ceilings"), "{section}");
    }
}
