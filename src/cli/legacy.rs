//! The spellings of the command line before `galerkin <capability> <verb>`: they keep working
//! for one release. [`translate`] rewrites them into the current grammar before clap parses,
//! and says on stderr what to write instead, e.g. `spacetime-gen` → `spacetime gen`,
//! `spectral FILE` → `spectral render FILE`, `bench spectral` → `spectral bench`,
//! `view` → `demo --view`, `--palette` → `--colormap`, `--range LO HI` → `--range LO,HI`,
//! a viewer's `--frames N` → `--quit-after N`, radiosity's `--view NAME` → `--viewpoint NAME`,
//! `--scenario` → `--generate`.

use std::ffi::OsString;

/// The options before the command that take a value (global options).
const GLOBAL_WITH_VALUE: &[&str] = &["--device"];

/// The verbs of a capability that takes `render` when none is given.
const SPECTRAL_VERBS: &[&str] = &["render", "view", "gen", "bench", "help"];
const SPACETIME_VERBS: &[&str] = &["render", "view", "gen", "convert", "bench", "help"];

/// Commands renamed as a whole: the old word and the words that replace it.
const RENAMED: &[(&str, &[&str])] = &[
    ("spacetime-gen", &["spacetime", "gen"]),
    ("spectral-gen", &["spectral", "gen"]),
    ("spacetime-convert", &["spacetime", "convert"]),
    ("view", &["demo", "--view"]),
];

/// The radiosity viewpoints (`--view NAME` before `--viewpoint`).
const VIEWPOINTS: &[&str] = &["living", "bedroom", "overview"];

/// Rewrites an old spelling into the current grammar. Returns the arguments to parse and a
/// deprecation note per rewrite. Arguments that are not UTF-8 are passed through untouched.
pub fn translate(args: Vec<OsString>) -> (Vec<OsString>, Vec<String>) {
    let Some(strings) = args.iter().map(|a| a.to_str().map(str::to_string)).collect::<Option<Vec<_>>>()
    else {
        return (args, Vec::new());
    };
    let (out, notes) = translate_strings(strings);
    (out.into_iter().map(OsString::from).collect(), notes)
}

fn translate_strings(mut a: Vec<String>) -> (Vec<String>, Vec<String>) {
    let mut notes = Vec::new();
    // The command's position: after argv[0] and any global options.
    let mut i = 1;
    while i < a.len() {
        if GLOBAL_WITH_VALUE.contains(&a[i].as_str()) {
            i += 2;
        } else if a[i].starts_with('-') {
            i += 1;
        } else {
            break;
        }
    }
    if i >= a.len() {
        return (a, notes);
    }
    let mut note = |old: &str, new: &str| {
        notes.push(format!("`{old}` is deprecated and will be removed in the next release: write `{new}`"))
    };
    if let Some((old, new)) = RENAMED.iter().find(|(old, _)| a[i] == *old) {
        note(&format!("galerkin {old}"), &format!("galerkin {}", new.join(" ")));
        a.splice(i..i + 1, new.iter().map(|s| s.to_string()));
    }
    match a[i].as_str() {
        "bench" => {
            let moved: Option<&[&str]> = match a.get(i + 1).map(String::as_str) {
                Some("spectral") => Some(&["spectral", "bench"]),
                Some("spacetime") => Some(&["spacetime", "bench"]),
                Some("radiosity") => Some(&["radiosity", "bench"]),
                Some("fluid") => Some(&["fluid", "bench"]),
                Some("fluid-reduced") => Some(&["fluid", "bench-reduced"]),
                _ => None,
            };
            if let Some(new) = moved {
                note(&format!("galerkin bench {}", a[i + 1]), &format!("galerkin {}", new.join(" ")));
                a.splice(i..i + 2, new.iter().map(|s| s.to_string()));
            }
        }
        cap @ ("spectral" | "spacetime") => {
            let verbs = if cap == "spectral" { SPECTRAL_VERBS } else { SPACETIME_VERBS };
            let next = a.get(i + 1).map(String::as_str);
            let is_help = matches!(next, Some("-h" | "--help"));
            if !is_help && !next.is_some_and(|v| verbs.contains(&v)) {
                note(&format!("galerkin {cap} [ARGS]"), &format!("galerkin {cap} render [ARGS]"));
                a.insert(i + 1, "render".to_string());
            }
        }
        _ => {}
    }
    // The verb is now at i + 1 (or the command has none).
    let command = a[i].clone();
    let verb = a.get(i + 1).cloned().unwrap_or_default();
    let viewer = matches!(
        (command.as_str(), verb.as_str()),
        ("spectral" | "spacetime", "render" | "view") | ("radiosity" | "fluid", "view") | ("demo", _)
    );
    let mut k = i + 1;
    while k < a.len() {
        match a[k].as_str() {
            "--" => break,
            "--palette" if command == "spectral" => {
                note("--palette", "--colormap");
                a[k] = "--colormap".into();
            }
            "--range" if command == "spectral" => {
                let number = |s: Option<&String>| s.is_some_and(|s| s.parse::<f64>().is_ok());
                if number(a.get(k + 1)) && number(a.get(k + 2)) {
                    let joined = format!("{},{}", a[k + 1], a[k + 2]);
                    note(&format!("--range {} {}", a[k + 1], a[k + 2]), &format!("--range {joined}"));
                    a.splice(k + 1..k + 3, [joined]);
                }
            }
            "--frames" if viewer => {
                note("--frames N (a viewer's frame count)", "--quit-after N");
                a[k] = "--quit-after".into();
            }
            "--view"
                if command == "radiosity"
                    && a.get(k + 1).is_some_and(|v| VIEWPOINTS.contains(&v.as_str())) =>
            {
                note("--view NAME (a viewpoint)", "--viewpoint NAME");
                a[k] = "--viewpoint".into();
            }
            "--scenario" if command == "spacetime" => {
                note("--scenario", "--generate");
                a[k] = "--generate".into();
            }
            _ => {}
        }
        k += 1;
    }
    (a, notes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(line: &str) -> (String, usize) {
        let args = line.split_whitespace().map(str::to_string).collect();
        let (out, notes) = translate_strings(args);
        (out.join(" "), notes.len())
    }

    #[test]
    fn current_spellings_pass_unchanged() {
        for line in [
            "galerkin spectral render a.vtu --colormap grey --range 0,1",
            "galerkin spectral --help",
            "galerkin spacetime gen --generate crack --out a.gst",
            "galerkin radiosity render s.toml --viewpoint bedroom",
            "galerkin fluid view m.safetensors --quit-after 3",
            "galerkin spectral bench --frames 3",
            "galerkin radiosity compare s.toml --frames 4,4",
            "galerkin --device llvmpipe info",
            "galerkin",
        ] {
            assert_eq!(run(line), (line.to_string(), 0), "{line}");
        }
    }

    #[test]
    fn old_spellings_are_rewritten_with_a_note() {
        let cases = [
            (
                "galerkin spacetime-gen --scenario crack --out a.gst",
                "galerkin spacetime gen --generate crack --out a.gst",
                2,
            ),
            (
                "galerkin spectral a.vtu --palette grey --range -1 2",
                "galerkin spectral render a.vtu --colormap grey --range -1,2",
                3,
            ),
            ("galerkin spectral --view --frames 3", "galerkin spectral render --view --quit-after 3", 2),
            (
                "galerkin --validation spectral-gen --out a.vtu",
                "galerkin --validation spectral gen --out a.vtu",
                1,
            ),
            ("galerkin spacetime-convert a.gst b.vtu", "galerkin spacetime convert a.gst b.vtu", 1),
            ("galerkin view --frames 5", "galerkin demo --view --quit-after 5", 2),
            ("galerkin bench fluid-reduced --quick", "galerkin fluid bench-reduced --quick", 1),
            ("galerkin --device x bench spectral --quick", "galerkin --device x spectral bench --quick", 1),
            (
                "galerkin radiosity view s.toml --view overview --frames 2",
                "galerkin radiosity view s.toml --viewpoint overview --quit-after 2",
                2,
            ),
            ("galerkin spacetime", "galerkin spacetime render", 1),
        ];
        for (old, new, notes) in cases {
            assert_eq!(run(old), (new.to_string(), notes), "{old}");
        }
    }

    #[test]
    fn a_viewer_flag_is_not_a_viewpoint() {
        // `radiosity render --view` (the viewer) keeps its meaning.
        assert_eq!(run("galerkin radiosity render s.toml --view").1, 0);
    }
}
