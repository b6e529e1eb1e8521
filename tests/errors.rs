//! Bad input and faults give one clear error (naming the package, the device, the buffer or
//! the file and line), a non-zero exit from the CLI, and no panic.

mod common;

use std::process::Command;

use galerkin::gpu::{vk, Buffer, Gpu, GpuDesc, GpuError, Image, ImageDesc, MemoryKind};

fn galerkin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_galerkin"));
    c.env_remove("GALERKIN_DEVICE").env("NO_COLOR", "1");
    c
}

#[test]
fn no_matching_device_names_what_was_seen() {
    let err = Gpu::new(&GpuDesc { device_name: Some("no such device 42".into()), ..GpuDesc::default() })
        .unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, GpuError::NoDevice { .. }), "{text}");
    assert!(text.contains("no such device 42") && text.contains("devices seen"), "{text}");
}

#[test]
fn a_missing_loader_names_the_package() {
    let desc = GpuDesc { loader_path: Some("/nonexistent/libvulkan.so.1".into()), ..GpuDesc::default() };
    let err = Gpu::new(&desc).unwrap_err();
    assert!(matches!(err, GpuError::NoLoader { .. }));
    assert!(err.to_string().contains("libvulkan1"), "{err}");
}

#[test]
fn the_cli_reports_a_missing_validation_layer() {
    let out =
        galerkin().args(["info", "--validation"]).env("VK_LAYER_PATH", "/nonexistent").output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("vulkan-validationlayers"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn the_cli_reports_no_driver() {
    let out = galerkin()
        .arg("info")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("mesa-vulkan-drivers"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn the_cli_names_file_and_line_of_a_bad_scene() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/demo.toml")).unwrap();
    let bad = good.replace("width = 640", "width = -640");
    let path = dir.join("bad.toml");
    std::fs::write(&path, &bad).unwrap();
    let out_dir = dir.join("out");
    let out = galerkin().args(["demo", "--scene"]).arg(&path).arg("--out").arg(&out_dir).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let line = bad.lines().position(|l| l.starts_with("width")).unwrap() + 1;
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&format!("bad.toml:{line}:")), "{stderr}");
    assert!(!out_dir.exists(), "nothing may be written for a bad scene");
}

#[test]
fn requests_over_device_limits_are_errors_naming_the_resource() {
    let gpu = common::gpu();
    let huge = gpu.caps().max_buffer_size.min(gpu.caps().max_memory_allocation_size) / 4 + 1024;
    let err =
        Buffer::<f32>::new(&gpu, "too big", huge, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
            .unwrap_err();
    assert!(matches!(err, GpuError::OverLimit { .. }), "{err}");
    assert!(err.to_string().contains("too big"), "{err}");

    let side = gpu.caps().max_image_dimension_2d + 1;
    let err = Image::new(&gpu, "too wide", ImageDesc::color_target(side, 4, vk::Format::R8G8B8A8_UNORM))
        .err()
        .unwrap();
    assert!(err.to_string().contains("too wide") && err.to_string().contains("maxImageDimension2D"), "{err}");

    // One binding cannot cover more than maxStorageBufferRange: an error that says to chunk.
    let gpu_small = common::gpu_with(|d| d.max_binding_bytes = Some(4096));
    let b = Buffer::<f32>::new(
        &gpu_small,
        "wide binding",
        2048,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryKind::GpuOnly,
    )
    .unwrap();
    let err = b.binding().unwrap_err();
    assert!(err.to_string().contains("wide binding") && err.to_string().contains("chunks"), "{err}");
    assert_eq!(b.binding_chunks().len(), 2);
}

#[test]
fn radiosity_compare_refuses_empty_sequences_before_any_work() {
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");
    for frames in ["0,0", "5,0"] {
        let out = galerkin()
            .args(["radiosity", "compare", scene, "--model", "/nonexistent/model", "--frames", frames])
            .output()
            .expect("ran");
        assert!(!out.status.success(), "--frames {frames}: exit 0");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--frames") && err.contains("1 to"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// `GpuDesc::default()` is the same in every process (an embedding host's environment does not
/// change it); `GpuDesc::from_env()` reads the `GALERKIN_*` variables (`make test` sets
/// GALERKIN_VALIDATION=1, so there the two differ).
#[test]
fn the_default_description_reads_nothing_from_the_environment() {
    let d = GpuDesc::default();
    assert!(!d.validation && d.device_name.is_none() && d.loader_path.is_none());
    #[cfg(feature = "fault-injection")]
    assert!(d.fail_allocation.is_none() && d.lose_device.is_none());
    let flag = std::env::var("GALERKIN_VALIDATION").is_ok_and(|v| !v.trim().is_empty() && v != "0");
    assert_eq!(GpuDesc::from_env().validation, flag);
    let device = std::env::var("GALERKIN_DEVICE").ok().filter(|v| !v.trim().is_empty());
    assert_eq!(GpuDesc::from_env().device_name, device);
}
