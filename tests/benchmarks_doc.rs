//! BENCHMARKS.md is a reference whose every figure can be traced (issue 50): each table either
//! carries `commit` and `command` columns, or sits under a provenance line in its section (what
//! a `##` or `###` heading opens) —
//! `Measured: commit `abc1234`, …, `galerkin …`` — naming the commit the figures were measured
//! at and the command that reproduces them. The tables `galerkin bench all --out` writes sit
//! between the document's markers, under the one line that run wrote.

use galerkin::bench::report::{BEGIN_MARKER, END_MARKER};

/// A provenance line: `Measured:` with a backticked commit hash (7 to 40 hex digits, optionally
/// `+dirty`) and a backticked command that reproduces the figures.
fn is_provenance(line: &str) -> Result<(), String> {
    let Some(rest) = line.trim_start().strip_prefix("Measured:") else {
        return Err("not a `Measured:` line".into());
    };
    let quoted: Vec<&str> = rest.split('`').skip(1).step_by(2).collect();
    let commit = quoted.iter().any(|q| {
        let hash = q.strip_suffix("+dirty").unwrap_or(q);
        (7..=40).contains(&hash.len()) && hash.bytes().all(|b| b.is_ascii_hexdigit())
    });
    let command = quoted.iter().any(|q| {
        ["galerkin ", "scripts/", "make ", "farm-bench ", "mpirun ", "cargo "]
            .iter()
            .any(|p| q.starts_with(p))
    });
    match (commit, command) {
        (true, true) => Ok(()),
        (false, _) => Err("no backticked commit hash".into()),
        (_, false) => {
            Err("no backticked command (galerkin, scripts/, make, farm-bench, mpirun, cargo)".into())
        }
    }
}

#[test]
fn the_provenance_form_is_recognised_and_can_fail() {
    assert!(is_provenance("Measured: commit `a43f229`, 2026-12-06, llvmpipe — Mesa, Xeon (2 cores), `galerkin bench all` (812 s).").is_ok());
    assert!(is_provenance("Measured: commit `a43f229+dirty`, `scripts/bench-ranks.sh`").is_ok());
    assert!(is_provenance("Measured: commit `zzzzzzz`, `galerkin bench all`").is_err());
    assert!(is_provenance("Measured: commit `a43f229`, by hand").is_err());
    assert!(is_provenance("Measured somewhere").is_err());
}

#[test]
fn every_benchmarks_table_names_its_commit_and_command() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/BENCHMARKS.md");
    let doc = std::fs::read_to_string(path).expect("BENCHMARKS.md");
    assert_eq!(
        doc.matches(BEGIN_MARKER).count(),
        1,
        "BENCHMARKS.md: the generated part's begin marker, once"
    );
    assert_eq!(doc.matches(END_MARKER).count(), 1, "BENCHMARKS.md: the generated part's end marker, once");
    let mut provenance_in_section: Option<usize> = None;
    let mut in_table = false;
    let mut fenced = false;
    let mut in_generated = false;
    let (mut tables, mut problems) = (0, Vec::new());
    for (i, line) in doc.lines().enumerate() {
        let n = i + 1;
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // A section is what a `##` or `###` heading opens; the generated part is one section
        // (its `###` headings are the commands' own, under the run's one provenance line).
        if line == BEGIN_MARKER || line == END_MARKER {
            in_generated = line == BEGIN_MARKER;
            provenance_in_section = None;
        } else if !in_generated && (line.starts_with("## ") || line.starts_with("### ")) {
            provenance_in_section = None;
        }
        if line.starts_with("Measured:") {
            match is_provenance(line) {
                Ok(()) => provenance_in_section = Some(n),
                Err(e) => problems.push(format!("BENCHMARKS.md:{n}: provenance line: {e}")),
            }
        }
        let is_row = line.starts_with('|');
        if is_row && !in_table {
            tables += 1;
            let header: Vec<String> = line.split('|').map(|c| c.trim().to_lowercase()).collect();
            let has_columns = header.iter().any(|c| c == "commit") && header.iter().any(|c| c == "command");
            if !has_columns && provenance_in_section.is_none() {
                problems.push(format!(
                    "BENCHMARKS.md:{n}: a table with neither commit and command columns nor a `Measured:` line before it in its section: {line}"
                ));
            }
        }
        in_table = is_row;
    }
    assert!(tables >= 10, "only {tables} tables found: the parser is not reading the document");
    assert!(problems.is_empty(), "{} table(s) without provenance:\n{}", problems.len(), problems.join("\n"));
}
