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
