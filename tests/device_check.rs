//! `scripts/device-check.sh` end to end on lavapipe, as on a machine with a real GPU and no
//! toolchain: the folder is packed (the binary this test suite built, stripped; the scenes; the
//! Vulkan loader and validation layer as .deb files from apt) and checked against the 60 MiB
//! that may be carried in, then run from a copy in another directory in its short mode (the
//! demo's reference checks with validation on), and its report names the device.

use std::path::Path;
use std::process::Command;

fn script(args: &[&str], envs: &[(&str, &str)]) -> (bool, String) {
    let out = Command::new("bash")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/device-check.sh"))
        .args(args)
        .envs(envs.iter().copied())
        .output()
        .expect("bash runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    (out.status.success(), text)
}

#[test]
fn a_packed_folder_runs_the_device_check_elsewhere() {
    let scratch = tempfile::Builder::new().prefix("galerkin-device-check-").tempdir().expect("scratch");
    let packed = scratch.path().join("packed");
    let bin = env!("CARGO_BIN_EXE_galerkin");
    let (ok, text) = script(&["--pack", packed.to_str().expect("utf-8")], &[("GALERKIN_BIN", bin)]);
    assert!(ok, "--pack (needs apt-get to reach its sources for the two .debs): {text}");
    let bytes: u64 = walk(&packed);
    assert!(bytes < 60 << 20, "the folder holds {bytes} bytes");
    for needed in ["galerkin", "device-check.sh", "scenes/radiosity/two_rooms_small.toml"] {
        assert!(packed.join(needed).exists(), "{needed} is not packed");
    }
    let debs: Vec<String> = std::fs::read_dir(packed.join("debs"))
        .expect("debs")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    assert!(
        debs.iter().any(|d| d.starts_with("libvulkan1_"))
            && debs.iter().any(|d| d.starts_with("vulkan-validationlayers_")),
        "{debs:?}"
    );
    // A folder packed into a non-empty directory is refused.
    let (ok, text) = script(&["--pack", packed.to_str().expect("utf-8")], &[("GALERKIN_BIN", bin)]);
    assert!(!ok && text.contains("not empty"), "{text}");
    // Carried elsewhere: run the copy, from its own script.
    let there = scratch.path().join("there");
    let copied = Command::new("cp").arg("-r").arg(&packed).arg(&there).status().expect("cp");
    assert!(copied.success());
    let out = Command::new("bash")
        .arg(there.join("device-check.sh"))
        .args(["--run", there.to_str().expect("utf-8"), "--short"])
        .current_dir(scratch.path())
        .output()
        .expect("bash runs");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "--run --short: {text}");
    let report = std::fs::read_to_string(there.join("out/device/device-check.md")).expect("the report");
    let info = std::fs::read_to_string(there.join("out/device/info.txt")).expect("info");
    let device = info.lines().next().expect("a device line");
    assert!(report.contains(device), "the report does not name the device ({device}): {report}");
    assert!(report.contains("bench gpu --quick") && report.contains('|'), "no ceilings table: {report}");
    assert!(
        there.join("out/device/demo").read_dir().is_ok_and(|mut d| d.next().is_some()),
        "no demo pictures"
    );
    // The unpacked loader and layer are the folder's own.
    assert!(there.join("root").is_dir());
}

fn walk(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .expect("dir")
        .flatten()
        .map(|e| {
            let p = e.path();
            if p.is_dir() {
                walk(&p)
            } else {
                e.metadata().map_or(0, |m| m.len())
            }
        })
        .sum()
}
