//! Files written whole or not at all (issue 24): each writer writes a uniquely named temporary
//! beside the target (`.NAME.PID.XXXXXX.partial`, through the `tempfile` crate), so two writers
//! of one name never share a temporary, and renames it over the target when complete; a writer
//! dropped unfinished removes its temporary. Readers see the old file or a new complete one,
//! never half of one; of two concurrent writers the last to finish wins.
//!
//! Interrupted runs leave nothing behind either: [`remove_on_interrupt`] (installed by the
//! command line) removes every unfinished temporary on SIGINT or SIGTERM before the process
//! exits, and a writer starting on NAME removes temporaries of NAME whose process is provably
//! gone (a killed run, `kill -9`): their PID has no `/proc` entry.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporaries being written now, removed on an interrupt.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Exit code of a command stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report it).
pub const INTERRUPTED_EXIT: i32 = 130;

/// Installs the handler that, on SIGINT or SIGTERM, removes every unfinished temporary, says
/// so on stderr and exits with [`INTERRUPTED_EXIT`]. Call once, early (the command line does).
pub fn remove_on_interrupt() -> Result<(), String> {
    ctrlc::set_handler(|| {
        // The handler runs on its own thread: waiting for the list is safe, and the lock is held
        // across every creation, rename and removal of a temporary, so each listed path is
        // either still a temporary or already gone, and no temporary exists unlisted.
        let list = unfinished();
        let removed = list.iter().filter(|p| std::fs::remove_file(p).is_ok()).count();
        eprintln!("interrupted: {removed} unfinished file(s) removed");
        std::process::exit(INTERRUPTED_EXIT);
    })
    .map_err(|e| format!("cannot handle SIGINT/SIGTERM: {e}"))
}

/// The list of unfinished temporaries, locked (a writer that panicked holding it leaves it
/// usable: the list itself is always consistent).
fn unfinished() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Removes temporaries of `name` in `dir` left by processes that no longer exist.
fn remove_stale(dir: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return; // no /proc: a process cannot be proved gone
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let prefix = format!(".{name}.");
    for entry in entries.flatten().take(100_000) {
        let file = entry.file_name();
        let Some(rest) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else { continue };
        let Some(pid) = rest.strip_suffix(".partial").and_then(|r| r.split('.').next()) else { continue };
        if pid.parse::<u32>().is_ok_and(|pid| !Path::new(&format!("/proc/{pid}")).exists()) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// A file being written to a temporary beside `target`.
pub struct AtomicFile {
    file: File,
    temp: Option<tempfile::TempPath>,
    target: PathBuf,
}

impl AtomicFile {
    /// Starts writing `target` (its directory must exist).
    pub fn create(target: &Path) -> std::io::Result<Self> {
        let dir = target.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let name = target.file_name().map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
        remove_stale(dir, &name);
        let prefix = format!(".{name}.{}.", std::process::id());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".partial");
        // The permissions `File::create` gives (0o666 less the umask), not the temporary's
        // owner-only default: a result is as readable as a file written directly.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let mut list = unfinished();
        let (file, temp) = builder.tempfile_in(dir)?.into_parts();
        list.push(temp.to_path_buf());
        drop(list);
        Ok(Self { file, temp: Some(temp), target: target.to_path_buf() })
    }

    /// The open temporary, to write to.
    pub fn file(&mut self) -> &mut File {
        &mut self.file
    }

    /// The temporary's path (for error messages).
    pub fn temp_path(&self) -> &Path {
        self.temp.as_deref().unwrap_or(&self.target)
    }

    /// The final name.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Flushes the data to disk and moves the temporary over the target.
    pub fn commit(mut self) -> std::io::Result<()> {
        self.file.sync_all()?;
        let temp = self.temp.take().ok_or_else(|| std::io::Error::other("committed twice"))?;
        let mut list = unfinished();
        let path = temp.to_path_buf();
        // On failure the returned TempPath drops here, under the lock, removing the temporary.
        let renamed = temp.persist(&self.target).map_err(|e| e.error);
        list.retain(|p| *p != path);
        renamed
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // Unfinished: the TempPath removes the file as it drops, under the lock.
        if let Some(temp) = self.temp.take() {
            let mut list = unfinished();
            let path = temp.to_path_buf();
            drop(temp);
            list.retain(|p| *p != path);
        }
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

    #[cfg(unix)]
    #[test]
    fn a_written_file_has_the_permissions_a_direct_write_gives() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().expect("scratch");
        let (atomic, direct) = (dir.path().join("atomic.png"), dir.path().join("direct.png"));
        write(&atomic, b"x").expect("atomic write");
        std::fs::write(&direct, b"x").expect("direct write");
        let mode = |p: &Path| std::fs::metadata(p).expect("metadata").permissions().mode() & 0o777;
        assert_eq!(mode(&atomic), mode(&direct), "not the owner-only temporary's 0o600");
    }

    #[test]
    fn a_writer_removes_temporaries_of_its_name_whose_process_is_gone() {
        let dir = tempfile::tempdir().expect("scratch");
        let target = dir.path().join("b.gst");
        // PID 999999999 is above any pid_max (at most 2²²): that process cannot exist.
        let dead = dir.path().join(".b.gst.999999999.AbC123.partial");
        let alive = dir.path().join(format!(".b.gst.{}.XyZ789.partial", std::process::id()));
        let other = dir.path().join(".c.gst.999999999.AbC123.partial");
        for p in [&dead, &alive, &other] {
            std::fs::write(p, b"half").expect("a temporary");
        }
        write(&target, b"whole").expect("written");
        assert!(!dead.exists(), "a dead process's temporary of this name stayed");
        assert!(alive.exists(), "a live process's temporary was removed");
        assert!(other.exists(), "another name's temporary was removed");
        assert!(unfinished().iter().all(|p| !p.starts_with(dir.path())));
    }
}
