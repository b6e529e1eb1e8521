//! Scene files: TOML read into a typed spec, every error naming the file and the line — the
//! line of the syntax or type error, or of the key a validation rule refuses.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// A scene file that cannot be read, parsed or validated.
#[derive(Debug, thiserror::Error)]
#[error("{}{}: {message}", path.display(), at_line(*line))]
pub struct SceneFileError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line (0 when the file could not be read at all).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// `:LINE` for a line of the file, nothing when the file could not be read at all (line 0).
fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}

/// The file's text. A file of another kind (a Wavefront OBJ, VTK XML, a binary file) is
/// refused saying what it is and what a scene file is, instead of a TOML parse error.
pub fn read(path: &Path) -> Result<String, SceneFileError> {
    let fail = |line, message: String| SceneFileError { path: path.to_path_buf(), line, message };
    let bytes = std::fs::read(path).map_err(|e| fail(0, e.to_string()))?;
    if let Some(kind) = other_kind(path, &bytes) {
        return Err(fail(1, kind));
    }
    String::from_utf8(bytes).map_err(|e| {
        let line = e.as_bytes()[..e.utf8_error().valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        fail(line, "not UTF-8 text: scene files are TOML".into())
    })
}

/// What a file that is not a scene is, judged by its name and first lines, with what to do.
fn other_kind(path: &Path, bytes: &[u8]) -> Option<String> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]);
    let code = head.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#'));
    let obj_line = |l: &str| {
        ["v ", "vn ", "vt ", "f ", "o ", "g ", "mtllib ", "usemtl "].iter().any(|k| l.starts_with(k))
    };
    let scene_help = "scene files are TOML: a radiosity scene names its OBJ geometry with `base = \"FILE.obj\"` and its deformation targets (see `galerkin radiosity render --help` and docs/radiosity.md); a fluid scene gives a [surface] section";
    if ext == "obj" || (code.clone().take(8).any(obj_line) && !head.contains('=')) {
        return Some(format!("this is a Wavefront OBJ file, not a scene: {scene_help}"));
    }
    if head.trim_start().starts_with("<?xml") || head.contains("<VTKFile") {
        return Some(format!(
            "this is an XML (VTK) file, not a scene: data sets are drawn by `galerkin spectral render FILE` or `galerkin spacetime render FILE`; {scene_help}"
        ));
    }
    if ext == "safetensors" {
        return Some("this is a model file (.safetensors), not a scene: pass it with --model".into());
    }
    if bytes.iter().take(4096).any(|&b| b == 0) {
        return Some(format!("this is a binary file, not a scene: {scene_help}"));
    }
    None
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// `text` (the contents of `path`) parsed as `T`.
pub fn parse<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, SceneFileError> {
    toml::from_str(text).map_err(|e| SceneFileError {
        path: path.to_path_buf(),
        line: e.span().map_or(1, |s| line_of(text, s.start)),
        message: e.message().to_string(),
    })
}

/// An error at the line of `text` that assigns `key` (`key = …`) or opens the table `[key]`;
/// failing that, the first line outside comments that mentions it (line 1 if none does).
pub fn error_at(text: &str, path: &Path, key: &str, message: String) -> SceneFileError {
    let code = |l: &str| l.split('#').next().unwrap_or_default().to_string();
    let assigns = |l: &str| {
        let t = code(l);
        let t = t.trim();
        t.strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('=')) || t == format!("[{key}]")
    };
    let line = text
        .lines()
        .position(assigns)
        .or_else(|| text.lines().position(|l| code(l).contains(key)))
        .map_or(1, |i| i + 1);
    SceneFileError { path: path.to_path_buf(), line, message }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unreadable_file_is_named_without_a_line_and_a_bad_line_with_it() {
        let missing = read(Path::new("/nonexistent/scene.toml")).unwrap_err().to_string();
        assert!(missing.starts_with("/nonexistent/scene.toml: "), "{missing}");
        let at = error_at("a = 1\nb = 2\n", Path::new("s.toml"), "b", "bad".into()).to_string();
        assert_eq!(at, "s.toml:2: bad");
    }
}
