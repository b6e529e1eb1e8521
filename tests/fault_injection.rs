//! Fault injection (issue 24): with `GALERKIN_FAIL_ALLOCATION=N` the N-th device allocation of
//! a command and every later one fail as out of memory. For every N up to the first that lets
//! the command finish, each command must exit with status 1 and an error naming the allocation
//! — no panic, no output file, and no Vulkan object leaked or misused (the validation layer is
//! on, and the command line checks its log after a failure too).

use std::process::Command;

/// Runs `args` with the N-th allocation failing; `None` once the command succeeds.
fn run_failing(args: &[&str], n: u64) -> Option<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(args)
        .env("GALERKIN_VALIDATION", "1")
        .env("GALERKIN_FAIL_ALLOCATION", n.to_string())
        .output()
        .expect("ran");
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    if out.status.success() {
        return None;
    }
    assert_eq!(out.status.code(), Some(1), "allocation {n} of {args:?}: {err}");
    Some(err)
}

#[test]
fn every_command_fails_cleanly_whichever_allocation_fails() {
    let dir = tempfile::Builder::new().prefix("galerkin-fault-").tempdir().expect("scratch");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");
    let commands: [(&str, Vec<String>); 3] = [
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
    ];
    for (file, args) in commands {
        let out = dir.path().join(file);
        let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
        let out_text = out.to_string_lossy().to_string();
        all.extend(["--out", &out_text]);
        let mut failed = 0;
        for n in 1..=200u64 {
            let Some(err) = run_failing(&all, n) else { break };
            failed += 1;
            assert!(
                err.contains("fault injection") && err.contains(&format!("allocation {n} ")),
                "{all:?}, {n}: {err}"
            );
            assert!(!err.contains("panicked") && !err.contains("validation error"), "{all:?}, {n}: {err}");
            assert!(!out.exists(), "{all:?}, {n}: an image was written");
        }
        assert!((3..200).contains(&failed), "{all:?}: {failed} failing allocations");
        assert!(out.exists(), "{all:?} never succeeded");
        eprintln!("{all:?}: failed cleanly at each of its first {failed} allocations");
    }
}
