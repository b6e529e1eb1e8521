//! Scene files: TOML read into a typed spec, every error naming the file and the line — the
//! line of the syntax or type error, or of the key a validation rule refuses.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// A scene file that cannot be read, parsed or validated.
#[derive(Debug, thiserror::Error)]
#[error("{path}:{line}: {message}")]
pub struct SceneFileError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line (0 when the file could not be read at all).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// The file's text.
pub fn read(path: &Path) -> Result<String, SceneFileError> {
    std::fs::read_to_string(path).map_err(|e| SceneFileError {
        path: path.to_path_buf(),
        line: 0,
        message: e.to_string(),
    })
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
