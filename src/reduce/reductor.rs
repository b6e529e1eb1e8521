//! One reduction workflow for every capability (DESIGN: `reduce`; what pyMOR calls a
//! "reductor"): a training runs as named stages — samples → full solves → bases → premultiplied
//! tensors → model — in a **work directory**, each stage's result kept there, so a training
//! killed at any moment resumes without redoing a finished stage.
//!
//! * The work directory remembers what it was made for (`work.json`: a description for people
//!   and a fingerprint — the scene's content, the options, the samples) and refuses another
//!   training ([`Reductor::open`]).
//! * Each stage has a folder `work/<stage>/`; a stage is finished when its `done` file holds the
//!   fingerprint, written after everything the stage keeps. A stage whose folder holds another
//!   fingerprint's leftovers starts from an empty folder; one that stopped part way (no `done`)
//!   gets its folder back as it was, so a long stage may keep its own partial results (the
//!   radiosity keeps each full solve as it finishes).
//! * Each stage reports its wall time and the process's peak memory during it
//!   ([`StageReport`], one line each, [`crate::process`]).
//!
//! The radiosity ([`crate::radiosity::train_stages`]) and the fluids
//! ([`crate::fluid::reduced::pipeline`]) both train through it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::process::{peak_memory_mb, reset_peak_memory};

/// What goes wrong in the workflow itself (the stages' own work fails with the capability's
/// error).
#[derive(Debug, thiserror::Error)]
pub enum ReductorError {
    /// The work directory cannot be read or written, or holds another training.
    #[error("work directory {path}: {message}")]
    Work {
        /// The file or folder.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The training was asked to stop after this stage ([`Reductor::stop_after`]); it resumes
    /// from the next.
    #[error("stopped after stage `{0}` as asked; run the same training again to resume")]
    Stopped(String),
}

/// One finished stage, for the log.
#[derive(Clone, Debug, PartialEq)]
pub struct StageReport {
    /// The stage's name.
    pub stage: String,
    /// Wall seconds.
    pub seconds: f64,
    /// The process's peak resident memory during the stage, MB (`None` where unknown).
    pub peak_mb: Option<f64>,
    /// Taken from the work directory, not computed.
    pub resumed: bool,
}

impl StageReport {
    /// The report as one log line: `stage bases: 12.3 s, peak memory 1,234 MB`.
    pub fn line(&self) -> String {
        let memory = match self.peak_mb {
            Some(mb) => format!("peak memory {mb:.0} MB"),
            None => "peak memory unknown".to_string(),
        };
        let how = if self.resumed { " (taken from the work directory)" } else { "" };
        format!("stage {}: {:.1} s, {memory}{how}", self.stage, self.seconds)
    }
}

/// A stage's clock: its start, with the peak memory reset.
#[derive(Debug)]
pub struct StageClock(Instant);

impl StageClock {
    /// Starts the clock and a new memory peak.
    pub fn start() -> Self {
        reset_peak_memory();
        Self(Instant::now())
    }

    /// The finished stage's report.
    pub fn done(self, stage: &str, resumed: bool) -> StageReport {
        StageReport {
            stage: stage.to_string(),
            seconds: self.0.elapsed().as_secs_f64(),
            peak_mb: peak_memory_mb(),
            resumed,
        }
    }
}

/// What a work directory was made for (`work.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct WorkKey {
    /// For people: the scene and the options.
    made_for: String,
    /// SHA-256 of everything the training depends on.
    fingerprint: String,
}

/// The SHA-256 (hex) of `parts`, each length-prefixed (so `("ab", "c")` and `("a", "bc")`
/// differ): a training's fingerprint.
pub fn fingerprint(parts: &[&[u8]]) -> String {
    let mut hash = Sha256::new();
    for part in parts {
        hash.update((part.len() as u64).to_le_bytes());
        hash.update(part);
    }
    hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// A training's work directory and its stages (see the module docs).
pub struct Reductor<'a> {
    work: PathBuf,
    fingerprint: String,
    writer: bool,
    stop_after: Option<String>,
    on_stage: Box<dyn FnMut(&StageReport) + 'a>,
}

impl<'a> Reductor<'a> {
    /// Opens (or starts) the work directory `work` for the training `made_for` (a description
    /// for people) with `fingerprint` ([`fingerprint`]); refuses a directory made for another
    /// training, naming it. Only a `writer` (rank 0 of a run over ranks; the only rank
    /// otherwise) writes; the others read what it wrote (they must wait for it, e.g. at a
    /// barrier, before [`Self::stage`]). `on_stage` hears every finished stage.
    pub fn open(
        work: &Path,
        made_for: &str,
        fingerprint: &str,
        writer: bool,
        on_stage: impl FnMut(&StageReport) + 'a,
    ) -> Result<Self, ReductorError> {
        let fail = |path: &Path, e: &dyn std::fmt::Display| ReductorError::Work {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let key_path = work.join("work.json");
        let key = WorkKey { made_for: made_for.to_string(), fingerprint: fingerprint.to_string() };
        match std::fs::read_to_string(&key_path) {
            Ok(text) => {
                let old: WorkKey = serde_json::from_str(&text).map_err(|e| {
                    fail(&key_path, &format!("not a galerkin work directory's key ({e}); give another work directory or remove it"))
                })?;
                if old.fingerprint != key.fingerprint {
                    return Err(fail(
                        work,
                        &format!(
                            "holds the training of {} (fingerprint {}), not of {} ({}); give another work directory or remove it",
                            old.made_for, old.fingerprint, key.made_for, key.fingerprint
                        ),
                    ));
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                if writer {
                    std::fs::create_dir_all(work).map_err(|e| fail(work, &e))?;
                    let text = serde_json::to_string_pretty(&key).map_err(|e| fail(&key_path, &e))?;
                    crate::atomic_file::write(&key_path, text.as_bytes()).map_err(|e| fail(&key_path, &e))?;
                }
            }
            Err(e) => return Err(fail(&key_path, &e)),
        }
        Ok(Self {
            work: work.to_path_buf(),
            fingerprint: fingerprint.to_string(),
            writer,
            stop_after: None,
            on_stage: Box::new(on_stage),
        })
    }

    /// Stops with [`ReductorError::Stopped`] once `stage` is finished and kept (what a kill
    /// right after it would leave; the tests of resuming use it).
    pub fn stop_after(mut self, stage: Option<&str>) -> Self {
        self.stop_after = stage.map(str::to_string);
        self
    }

    /// The work directory.
    pub fn work(&self) -> &Path {
        &self.work
    }

    /// Whether `stage` is finished and kept in the work directory.
    pub fn finished(&self, stage: &str) -> bool {
        std::fs::read_to_string(self.work.join(stage).join("done")).is_ok_and(|f| f == self.fingerprint)
    }

    /// Runs `stage`: if it is finished, `load(folder)` reads its result back; otherwise
    /// `compute(folder, writer)` makes it (a writer also keeps it in `folder`, which holds
    /// whatever an earlier, stopped attempt of the same training left), then the stage is
    /// marked finished. Either way the stage's report goes to `on_stage`.
    pub fn stage<T, E: From<ReductorError>>(
        &mut self,
        stage: &str,
        load: impl FnOnce(&Path) -> Result<T, E>,
        compute: impl FnOnce(&Path, bool) -> Result<T, E>,
    ) -> Result<T, E> {
        let clock = StageClock::start();
        let folder = self.work.join(stage);
        let fail = |path: &Path, e: std::io::Error| ReductorError::Work {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let resumed = self.finished(stage);
        let value = if resumed {
            load(&folder)?
        } else {
            if self.writer {
                let owner = folder.join("fingerprint");
                let ours = std::fs::read_to_string(&owner).is_ok_and(|f| f == self.fingerprint);
                if !ours && folder.exists() {
                    std::fs::remove_dir_all(&folder).map_err(|e| fail(&folder, e))?;
                }
                std::fs::create_dir_all(&folder).map_err(|e| fail(&folder, e))?;
                crate::atomic_file::write(&owner, self.fingerprint.as_bytes())
                    .map_err(|e| fail(&owner, e))?;
            }
            let value = compute(&folder, self.writer)?;
            if self.writer {
                let done = folder.join("done");
                crate::atomic_file::write(&done, self.fingerprint.as_bytes()).map_err(|e| fail(&done, e))?;
            }
            value
        };
        (self.on_stage)(&clock.done(stage, resumed));
        if self.stop_after.as_deref() == Some(stage) {
            return Err(ReductorError::Stopped(stage.to_string()).into());
        }
        Ok(value)
    }

    /// Removes the work directory (after the model is written, unless it is to be kept).
    pub fn remove(self) -> Result<(), ReductorError> {
        if self.writer {
            std::fs::remove_dir_all(&self.work)
                .map_err(|e| ReductorError::Work { path: self.work.clone(), message: e.to_string() })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct Fail(String);
    impl From<ReductorError> for Fail {
        fn from(e: ReductorError) -> Self {
            Fail(e.to_string())
        }
    }

    fn read(dir: &Path) -> Result<String, Fail> {
        std::fs::read_to_string(dir.join("value")).map_err(|e| Fail(e.to_string()))
    }

    fn write(dir: &Path, value: &str) -> Result<String, Fail> {
        std::fs::write(dir.join("value"), value).map_err(|e| Fail(e.to_string()))?;
        Ok(value.to_string())
    }

    /// A stage computed once is read back on the next run; a stopped run resumes at the next
    /// stage; another training's fingerprint is refused, naming both.
    #[test]
    fn stages_resume_and_another_training_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let work = dir.path().join("work");
        let key = fingerprint(&[b"scene", b"options"]);
        let mut reports = Vec::new();
        let mut computed = Vec::new();
        {
            // A run that finishes stage `one` and is killed before `two`.
            let mut r =
                Reductor::open(&work, "a test", &key, true, |s: &StageReport| reports.push(s.clone()))
                    .unwrap();
            let one = r.stage("one", read, |d, _| {
                computed.push("one");
                write(d, "1")
            });
            assert_eq!(one.unwrap(), "1");
        }
        let mut r = Reductor::open(&work, "a test", &key, true, |_: &StageReport| {}).unwrap();
        let one: String = r.stage("one", read, |_, _| Err(Fail("must not recompute".into()))).unwrap();
        let two: String = r.stage("two", read, |d, _| write(d, "2")).unwrap();
        assert_eq!((one.as_str(), two.as_str()), ("1", "2"));
        assert!(r.finished("one") && r.finished("two"));
        assert_eq!(computed, ["one"]);
        assert!(reports.iter().all(|s| !s.resumed && s.line().starts_with("stage one: ")));

        let other = fingerprint(&[b"scene", b"other options"]);
        let e = Reductor::open(&work, "another test", &other, true, |_: &StageReport| {}).err().unwrap();
        let e = e.to_string();
        assert!(e.contains("a test") && e.contains(&key) && e.contains(&other), "{e}");
    }

    /// `stop_after` stops after the stage is kept; a stage interrupted part way (no `done`)
    /// finds its folder as it left it.
    #[test]
    fn a_stopped_stage_keeps_its_partial_results() {
        let dir = tempfile::tempdir().unwrap();
        let work = dir.path().join("work");
        let key = fingerprint(&[b"x"]);
        let mut r =
            Reductor::open(&work, "x", &key, true, |_: &StageReport| {}).unwrap().stop_after(Some("a"));
        let e = r.stage("a", read, |d, _| write(d, "a")).unwrap_err();
        assert!(e.0.contains("stopped after stage `a`"), "{}", e.0);
        // A stage that fails part way, after keeping a partial result.
        let e = r.stage::<String, Fail>("b", read, |d, _| {
            std::fs::write(d.join("partial"), "half").unwrap();
            Err(Fail("killed".into()))
        });
        assert!(e.is_err() && !r.finished("b"));
        let mut r = Reductor::open(&work, "x", &key, true, |_: &StageReport| {}).unwrap();
        let b: String = r
            .stage("b", read, |d, _| {
                let partial = std::fs::read_to_string(d.join("partial")).map_err(|e| Fail(e.to_string()))?;
                write(d, &format!("{partial} and the rest"))
            })
            .unwrap();
        assert_eq!(b, "half and the rest");
        r.remove().unwrap();
        assert!(!work.exists());
    }
}
