//! What the fuzz targets share: the loaders read paths, so each input is written to a scratch
//! file of this process (libFuzzer runs one input at a time per process) before it is read.

use std::path::PathBuf;

/// A scratch directory of this process, made once.
pub fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("galerkin-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    dir
}

/// Writes `bytes` to the scratch file `name` and returns its path.
pub fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    let path = scratch_dir().join(name);
    std::fs::write(&path, bytes).expect("the scratch file");
    path
}

/// `data` cut at the separator line `--8<--` into at most `n` parts (the rest empty).
pub fn parts(data: &[u8], n: usize) -> Vec<&[u8]> {
    const SEP: &[u8] = b"\n--8<--\n";
    let mut out = Vec::with_capacity(n);
    let mut rest = data;
    while out.len() + 1 < n {
        match rest.windows(SEP.len()).position(|w| w == SEP) {
            Some(i) => {
                out.push(&rest[..i]);
                rest = &rest[i + SEP.len()..];
            }
            None => break,
        }
    }
    out.push(rest);
    out.resize(n, &[]);
    out
}
