//! Fault injection (issue 24): with `GALERKIN_FAIL_ALLOCATION=N` the N-th device allocation of
//! a command and every later one fail as out of memory; with `GALERKIN_LOSE_DEVICE=N` the
//! wait for the N-th submission reports the device lost and every later submission fails as
//! lost. For every N up to the first that lets the command finish, each command must exit with
//! status 1 and an error naming the fault — no panic, no output file, and no Vulkan object
//! leaked or misused (the validation layer is on, and the command line checks its log after a
//! failure too). A new `Gpu` made after a lost one works.

mod common;

use std::process::Command;

use galerkin::gpu::GpuError;

/// Runs `args` with fault `variable` set to N; `None` once the command succeeds.
fn run_with_fault(args: &[&str], variable: &str, n: u64) -> Option<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(args)
        .env("GALERKIN_VALIDATION", "1")
        .env(variable, n.to_string())
        .output()
        .expect("ran");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    if out.status.success() {
        return None;
    }
    assert_eq!(out.status.code(), Some(1), "{variable}={n} on {args:?}: {err}");
    Some(err)
}

/// The three rendering commands (argument lists, output file name) the faults are tried on.
fn commands() -> [(&'static str, Vec<String>); 3] {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");
    [
        ("spectral.png", vec!["spectral".into(), "render".into(), "--size".into(), "64x48".into()]),
        (
            "spacetime.png",
            vec![
                "spacetime".into(),
                "render".into(),
                "--elements".into(),
                "2000".into(),
                "--size".into(),
                "64x48".into(),
            ],
        ),
        (
            "radiosity.png",
            vec!["radiosity".into(), "render".into(), scene.into(), "--size".into(), "64x48".into()],
        ),
    ]
}

/// Runs every command with fault `variable` at 1, 2, … until it succeeds; `check(n, stderr)`
/// judges each failure's message. Returns the failures per command.
fn fail_each_in_turn(variable: &str, check: impl Fn(u64, &str) -> bool) -> Vec<usize> {
    let dir = tempfile::Builder::new().prefix("galerkin-fault-").tempdir().expect("scratch");
    let mut counts = Vec::new();
    for (file, args) in commands() {
        let out = dir.path().join(file);
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        let out_text = out.to_string_lossy().to_string();
        all.extend(["--out", &out_text]);
        let mut failed = 0;
        for n in 1..=200u64 {
            let Some(err) = run_with_fault(&all, variable, n) else { break };
            failed += 1;
            assert!(check(n, &err), "{all:?}, {variable}={n}: {err}");
            assert!(!err.contains("panicked") && !err.contains("validation error"), "{all:?}, {n}: {err}");
            assert!(!out.exists(), "{all:?}, {n}: an image was written");
        }
        assert!((1..200).contains(&failed), "{all:?}: {failed} failures of {variable}");
        assert!(out.exists(), "{all:?} never succeeded");
        eprintln!("{all:?}: failed cleanly at each of its first {failed} ({variable})");
        counts.push(failed);
    }
    counts
}

#[test]
fn every_command_fails_cleanly_whichever_allocation_fails() {
    let counts = fail_each_in_turn("GALERKIN_FAIL_ALLOCATION", |n, err| {
        err.contains("fault injection") && err.contains(&format!("allocation {n} "))
    });
    assert!(counts.iter().all(|&c| c >= 3), "{counts:?}");
}

#[test]
fn every_command_fails_cleanly_whichever_submission_loses_the_device() {
    fail_each_in_turn("GALERKIN_LOSE_DEVICE", |_, err| {
        err.contains("device was lost") && err.contains("fault injection")
    });
}

#[test]
fn a_new_gpu_works_after_the_device_was_lost() {
    {
        let lost = common::gpu_with(|d| d.lose_device = Some(2));
        lost.run(|_| ()).expect("the first submission finishes");
        let e = lost.run(|_| ()).expect_err("the second reports the device lost");
        assert!(matches!(e, GpuError::DeviceLost { .. }), "{e}");
        let e = lost.run(|_| ()).expect_err("later submissions are refused");
        assert!(matches!(e, GpuError::DeviceLost { .. }), "{e}");
        // Dropping it checks the validation log: nothing leaked, nothing misused.
    }
    let fresh = common::gpu();
    fresh.run(|_| ()).expect("a new Gpu works");
}
