//! An interrupted command leaves nothing behind (issue 24): `spacetime gen` streaming a large
//! `.gst` is stopped by SIGINT (Ctrl-C) and by SIGTERM while it writes; each time it exits with
//! code 130, says so, and the directory holds neither the target nor its temporary.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Waits (at most 60 s) until `dir` holds a temporary with data in it.
fn wait_for_partial(dir: &Path) {
    let start = Instant::now();
    loop {
        let writing = std::fs::read_dir(dir).expect("dir").flatten().any(|e| {
            e.file_name().to_string_lossy().ends_with(".partial") && e.metadata().is_ok_and(|m| m.len() > 0)
        });
        if writing {
            return;
        }
        assert!(start.elapsed() < Duration::from_secs(60), "no temporary appeared in {}", dir.display());
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn an_interrupted_writer_removes_its_temporary_and_exits_130() {
    for signal in ["INT", "TERM"] {
        let dir = tempfile::Builder::new().prefix("galerkin-interrupt-").tempdir().expect("scratch");
        let target = dir.path().join("big.gst");
        let child = Command::new(env!("CARGO_BIN_EXE_galerkin"))
            .args(["spacetime", "gen", "--generate", "pulses", "--elements", "50000000", "--out"])
            .arg(&target)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("galerkin starts");
        wait_for_partial(dir.path());
        let sent = Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status();
        assert!(sent.is_ok_and(|s| s.success()), "kill -{signal}");
        let out = child.wait_with_output().expect("galerkin exits");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "SIG{signal}: {stderr}");
        assert!(stderr.contains("interrupted: 1 unfinished file(s) removed"), "SIG{signal}: {stderr}");
        let left: Vec<_> =
            std::fs::read_dir(dir.path()).expect("dir").flatten().map(|e| e.file_name()).collect();
        assert!(left.is_empty(), "SIG{signal}: left behind {left:?}");
    }
}

/// The frames a snapshot directory's header declares (0 while there is none).
fn declared_frames(dir: &Path) -> usize {
    std::fs::read_to_string(dir.join("snapshots.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["frames"].as_u64())
        .map_or(0, |k| k as usize)
}

/// A simulation stopped by Ctrl-C between frames or while it writes one leaves a valid shorter
/// run: the reader opens it, and its frames are bit for bit the first frames of an uninterrupted
/// run of the same scene. First into a new directory, then with `--force` over a finished run
/// (the old header goes before the old frames, so the old run's frame count never describes
/// the new files).
#[test]
fn an_interrupted_simulation_leaves_a_valid_shorter_run() {
    use galerkin::fluid::snapshots::SnapshotReader;
    let scratch = tempfile::Builder::new().prefix("galerkin-interrupt-sim-").tempdir().expect("scratch");
    let simulate = |dir: &Path, frames: &str| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_galerkin"));
        command
            .args([
                "fluid",
                "simulate",
                "scenes/fluid/tunnel_small.toml",
                "--force",
                "--frames",
                frames,
                "--out",
            ])
            .arg(dir)
            .stdout(Stdio::null())
            .stderr(Stdio::piped());
        command
    };
    let whole = scratch.path().join("whole");
    let status = simulate(&whole, "40").status().expect("galerkin runs");
    assert!(status.success());
    let whole = SnapshotReader::open(&whole).expect("the uninterrupted run");
    let stopped = scratch.path().join("stopped");
    for round in ["new directory", "over a finished 40-frame run"] {
        if round != "new directory" {
            assert!(simulate(&stopped, "40").status().expect("galerkin runs").success());
        }
        let modified =
            |dir: &Path| std::fs::metadata(dir.join("snapshots.json")).and_then(|m| m.modified()).ok();
        let before = modified(&stopped);
        let child = simulate(&stopped, "1000000").spawn().expect("galerkin starts");
        let start = Instant::now();
        while modified(&stopped) == before || declared_frames(&stopped) < 3 {
            assert!(start.elapsed() < Duration::from_secs(60), "{round}: no frames appeared");
            std::thread::sleep(Duration::from_millis(5));
        }
        let sent = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
        assert!(sent.is_ok_and(|s| s.success()), "kill -INT");
        let out = child.wait_with_output().expect("galerkin exits");
        assert_eq!(out.status.code(), Some(130), "{round}: {}", String::from_utf8_lossy(&out.stderr));
        let run = SnapshotReader::open(&stopped).unwrap_or_else(|e| panic!("{round}: {e}"));
        let k = run.meta().frames;
        assert!(k >= 3, "{round}: {k} frames");
        for q in ["u", "p", "f", "g", "h"] {
            for frame in 0..k.min(whole.meta().frames) {
                let (a, b) = (run.frame(q, frame).expect("frame"), whole.frame(q, frame).expect("frame"));
                assert!(a == b, "{round}: frame {frame} of {q} differs from the uninterrupted run's");
            }
        }
        let partial = std::fs::read_dir(&stopped)
            .expect("dir")
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
            .count();
        assert_eq!(partial, 0, "{round}: temporaries left");
    }
}
