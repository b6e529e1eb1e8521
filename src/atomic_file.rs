//! Files written whole or not at all (issue 24): each writer writes a uniquely named temporary
//! beside the target (`.NAME.XXXXXX.partial`, through the `tempfile` crate), so two writers of
//! one name never share a temporary, and renames it over the target when complete; a writer
//! dropped unfinished removes its temporary. Readers see the old file or a new complete one,
//! never half of one; of two concurrent writers the last to finish wins.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A file being written to a temporary beside `target`.
pub struct AtomicFile {
    file: File,
    temp: tempfile::TempPath,
    target: PathBuf,
}

impl AtomicFile {
    /// Starts writing `target` (its directory must exist).
    pub fn create(target: &Path) -> std::io::Result<Self> {
        let dir = target.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let name = target.file_name().map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
        let (file, temp) = tempfile::Builder::new()
            .prefix(&format!(".{name}."))
            .suffix(".partial")
            .tempfile_in(dir)?
            .into_parts();
        Ok(Self { file, temp, target: target.to_path_buf() })
    }

    /// The open temporary, to write to.
    pub fn file(&mut self) -> &mut File {
        &mut self.file
    }

    /// The temporary's path (for error messages).
    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// The final name.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Flushes the data to disk and moves the temporary over the target.
    pub fn commit(self) -> std::io::Result<()> {
        self.file.sync_all()?;
        drop(self.file);
        self.temp.persist(&self.target).map_err(|e| e.error)
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl std::io::Seek for AtomicFile {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.file.seek(pos)
    }
}

/// Writes `bytes` to `target` whole or not at all.
pub fn write(target: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = AtomicFile::create(target)?;
    f.file().write_all(bytes)?;
    f.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_appears_whole_and_an_unfinished_one_leaves_nothing() {
        let dir = tempfile::tempdir().expect("scratch");
        let target = dir.path().join("a.txt");
        write(&target, b"first").expect("write");
        let mut unfinished = AtomicFile::create(&target).expect("create");
        unfinished.file().write_all(b"half").expect("write");
        let temp = unfinished.temp_path().to_path_buf();
        assert!(temp.exists() && temp != target);
        drop(unfinished);
        assert!(!temp.exists(), "the temporary outlived its writer");
        assert_eq!(std::fs::read(&target).expect("read"), b"first");
        // Two writers of one name at once: separate temporaries, the last commit wins.
        let (mut a, mut b) =
            (AtomicFile::create(&target).expect("a"), AtomicFile::create(&target).expect("b"));
        assert_ne!(a.temp_path(), b.temp_path());
        a.file().write_all(b"from a").expect("a");
        b.file().write_all(b"from b").expect("b");
        a.commit().expect("a");
        b.commit().expect("b");
        assert_eq!(std::fs::read(&target).expect("read"), b"from b");
        assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 1, "temporaries left");
    }
}
