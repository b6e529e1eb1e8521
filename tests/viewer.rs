//! The viewer, run as a child process (winit allows one event loop per process) under Xvfb:
//! it must present frames, save a screenshot copied back from the presented swapchain image,
//! and exit 0 with validation on; the screenshot's pixels are checked against the CPU reference.
#![cfg(feature = "viewer")]

mod common;

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};

use galerkin::demo::field::check_colours;
use galerkin::demo::scene::DemoScene;
use galerkin::render::{read_png_rgba8, Colormap};

/// An Xvfb server on a free display, killed on drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb runs (Debian package xvfb; scripts/install-deps.sh installs it)");
        let mut line = String::new();
        BufReader::new(child.stdout.take().unwrap()).read_line(&mut line).unwrap();
        let display = format!(":{}", line.trim());
        assert!(line.trim().parse::<u32>().is_ok(), "Xvfb did not report a display: {line:?}");
        Xvfb { child, display }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `galerkin demo --view --quit-after frames [extra…]` on display `x` and returns the screenshot.
fn run_viewer(x: &Xvfb, name: &str, frames: u32, extra: &[&str]) -> (u32, u32, Vec<u8>) {
    let scratch = tempfile::Builder::new()
        .prefix(&format!("galerkin-viewer-{name}-"))
        .tempdir()
        .expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let shot = dir.join("shot.png");
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/demo.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["demo", "--view", "--validation", "--quit-after", &frames.to_string(), "--scene"])
        .arg(&scene_path)
        .args(extra)
        .arg("--screenshot")
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "galerkin view failed: {stderr}");
    read_png_rgba8(&shot).unwrap()
}

/// Checks a screenshot against the CPU reference of the demo scene at its own size.
/// Pixels of an RGBA8 screenshot that are not the viewer's background.
fn drawn_pixels(rgba: &[u8]) -> usize {
    let background = galerkin::render::BACKGROUND.map(|v| (v * 255.0).round() as u8);
    rgba.chunks_exact(4).filter(|p| p[..3] != background[..3]).count()
}

fn check_screenshot(w: u32, h: u32, rgba: &[u8]) {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/demo.toml");
    let scene = DemoScene::load(&scene_path).unwrap();
    let colormap = Colormap::by_name(&scene.colormap_name()).unwrap();
    let background = [0.12f32, 0.12, 0.14, 1.0].map(|v| (v * 255.0).round() as u8);
    let check = check_colours(
        &scene.camera,
        &scene.field.coefficients,
        &colormap,
        scene.ramp(),
        w,
        h,
        rgba,
        background,
    );
    assert!(check.passed(), "{} pixels differ; first: {:?}", check.failures, check.first_failure);
    assert!(check.checked > (w * h / 5) as usize, "only {} covered pixels", check.checked);
}

#[test]
fn the_viewer_presents_frames_and_its_screenshot_matches_the_reference() {
    let x = Xvfb::start();
    let (w, h, rgba) = run_viewer(&x, "plain", 4, &[]);
    let scene = DemoScene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/demo.toml")).unwrap();
    assert_eq!((w, h), (scene.image.width, scene.image.height), "window size");
    check_screenshot(w, h, &rgba);
}

#[test]
fn the_viewer_follows_a_resize() {
    let x = Xvfb::start();
    let (w, h, rgba) = run_viewer(&x, "resize", 8, &["--resize-to", "320x200"]);
    assert_eq!((w, h), (320, 200), "the swapchain and target follow the new window size");
    check_screenshot(w, h, &rgba);
}

#[test]
fn the_spacetime_viewer_animates_t() {
    let x = Xvfb::start();
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let shot = dir.join("shot.png");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args([
            "spacetime",
            "view",
            "--validation",
            "--generate",
            "pulses",
            "--elements",
            "6000",
            "--time",
            "0.2",
        ])
        .args(["--play", "--quit-after", "6", "--size", "320x200", "--screenshot"])
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "galerkin spacetime --view failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // "viewer: 6 frames, t from 0.2000 to T": playing moved t forward.
    let line = stdout.lines().find(|l| l.starts_with("viewer:")).expect("the viewer's summary line");
    let times: Vec<f64> = line.split_whitespace().filter_map(|w| w.parse().ok()).collect();
    assert_eq!(times.len(), 3, "{line}");
    assert_eq!(times[0], 6.0, "{line}");
    assert!(times[2] > times[1], "t did not advance: {line}");
    let (w, h, rgba) = read_png_rgba8(&shot).unwrap();
    assert_eq!((w, h), (320, 200));
    let drawn = drawn_pixels(&rgba);
    assert!(drawn > (w * h / 10) as usize, "only {drawn} pixels drawn");
}

/// Runs `galerkin ARGS… --validation --size SIZE --screenshot …` on display `x`; returns its
/// stdout and the screenshot.
fn run_view(x: &Xvfb, name: &str, args: &[&str], size: &str) -> (String, u32, u32, Vec<u8>) {
    let scratch = tempfile::Builder::new()
        .prefix(&format!("galerkin-viewer-{name}-"))
        .tempdir()
        .expect("a scratch directory");
    let shot = scratch.path().join("shot.png");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(args)
        .args(["--validation", "--size", size, "--screenshot"])
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(out.status.success(), "galerkin {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    let (w, h, rgba) = read_png_rgba8(&shot).unwrap();
    (String::from_utf8_lossy(&out.stdout).to_string(), w, h, rgba)
}

/// Runs `galerkin spectral view … --quit-after N` at 320×200 on display `x`; returns its stdout
/// and the screenshot's share of drawn pixels.
fn run_spectral_viewer(x: &Xvfb, name: &str, args: &[&str], frames: u32) -> (String, f64) {
    let frames = frames.to_string();
    let args: Vec<&str> = ["spectral", "view"]
        .into_iter()
        .chain(args.iter().copied())
        .chain(["--quit-after", &frames])
        .collect();
    let (stdout, w, h, rgba) = run_view(x, name, &args, "320x200");
    assert_eq!((w, h), (320, 200));
    let drawn = drawn_pixels(&rgba);
    (stdout, drawn as f64 / f64::from(w * h))
}

/// Viewers wide enough show the colour bar their PNG pictures carry, beside the picture: the
/// right-hand strip of `BAR_WIDTH` pixels is the legend (mostly white, with both ends of the
/// colour map, as `plot::colour_bar_rgba` draws them), and the picture keeps the rest (no
/// white in it). The 320-pixel windows of the other tests are too narrow and show none.
#[test]
fn wide_viewers_show_the_colour_legend_beside_the_picture() {
    use galerkin::plot::BAR_WIDTH;
    let x = Xvfb::start();
    let map = Colormap::by_name("cool-warm").expect("cool-warm");
    let views: [&[&str]; 2] = [
        &["spectral", "view", "--generate", "annulus", "--colormap", "cool-warm", "--quit-after", "3"],
        &["spacetime", "view", "--generate", "pulses", "--elements", "6000", "--time", "0.2"],
    ];
    for args in views {
        let mut args = args.to_vec();
        if args[0] == "spacetime" {
            args.extend(["--colormap", "cool-warm", "--quit-after", "3"]);
        }
        let (_, w, h, rgba) = run_view(&x, args[0], &args, "800x400");
        assert_eq!((w, h), (800, 400));
        let strip = w - BAR_WIDTH;
        let white = |p: &[u8]| p[..3] == [255, 255, 255];
        let (mut legend_white, mut picture_white, mut legend) = (0, 0, Vec::new());
        for y in 0..h {
            for x in 0..w {
                let p = &rgba[4 * (y * w + x) as usize..][..4];
                if x >= strip {
                    legend_white += usize::from(white(p));
                    legend.push([p[0], p[1], p[2]]);
                } else {
                    picture_white += usize::from(white(p));
                }
            }
        }
        let area = (BAR_WIDTH * h) as usize;
        assert!(legend_white > area / 2, "{}: {legend_white} of {area} legend pixels white", args[0]);
        assert!(
            picture_white < (strip * h / 100) as usize,
            "{}: {picture_white} white pixels in the picture",
            args[0]
        );
        for t in [0.0, 1.0] {
            let c = map.sample((t + 0.5 / 256.0f64).min(1.0 - 0.5 / 256.0));
            let want = [(255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8];
            assert!(legend.contains(&want), "{}: end {t} of the map is not in the legend", args[0]);
        }
        let drawn = (0..h)
            .flat_map(|y| (0..strip).map(move |x| (x, y)))
            .filter(|&(x, y)| drawn_pixels(&rgba[4 * (y * w + x) as usize..][..4]) == 1)
            .count();
        assert!(drawn > (strip * h / 20) as usize, "{}: only {drawn} pixels of the picture drawn", args[0]);
    }
}

/// The fluid and radiosity viewers show their legends too: the fluid's speed on viridis (both
/// ends in the strip), the radiosity's tone-map grey ramp (a column of greys rising from near
/// black to near white over 100 rows or more).
#[test]
fn fluid_and_radiosity_viewers_show_their_legend() {
    use galerkin::plot::BAR_WIDTH;
    let x = Xvfb::start();
    let tunnel = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    let rooms = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let strip_of = |w: u32, h: u32, rgba: &[u8]| -> Vec<Vec<[u8; 3]>> {
        (w - BAR_WIDTH..w)
            .map(|x| {
                (0..h)
                    .map(|y| {
                        let p = &rgba[4 * (y * w + x) as usize..][..3];
                        [p[0], p[1], p[2]]
                    })
                    .collect()
            })
            .collect()
    };
    let (_, w, h, rgba) = run_view(
        &x,
        "fluid-legend",
        &["fluid", "view", &tunnel.to_string_lossy(), "--play", "--quit-after", "3"],
        "800x400",
    );
    let columns = strip_of(w, h, &rgba);
    let map = Colormap::viridis();
    for t in [0.0, 1.0] {
        let c = map.sample((t + 0.5 / 256.0f64).min(1.0 - 0.5 / 256.0));
        let want = [(255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8];
        let near = |p: &[u8; 3]| (0..3).all(|k| p[k].abs_diff(want[k]) <= 8);
        assert!(columns.iter().flatten().any(near), "fluid view: end {t} of viridis is not in the legend");
    }
    let (_, w, h, rgba) = run_view(
        &x,
        "radiosity-legend",
        &["radiosity", "view", &rooms.to_string_lossy(), "--quit-after", "3"],
        "800x400",
    );
    let ramp = strip_of(w, h, &rgba).iter().any(|column| {
        let greys: Vec<u8> = column.iter().filter(|p| p[0] == p[1] && p[1] == p[2]).map(|p| p[0]).collect();
        // The longest run of non-increasing greys (the bar runs from white at the top down).
        let (mut best, mut start) = ((0, 0u8, 0u8), 0);
        for k in 1..=greys.len() {
            if k == greys.len() || greys[k] > greys[k - 1] {
                let run = &greys[start..k];
                if run.len() > best.0 {
                    best = (run.len(), *run.last().unwrap_or(&0), *run.first().unwrap_or(&0));
                }
                start = k;
            }
        }
        best.0 >= 100 && best.1 <= 16 && best.2 >= 230
    });
    assert!(ramp, "radiosity view: no tone-map grey ramp in the legend");
}

#[test]
fn the_spectral_viewer_shows_a_surface() {
    let x = Xvfb::start();
    let (stdout, drawn) = run_spectral_viewer(
        &x,
        "surface",
        &["--generate", "artery", "--order", "3", "--isolines", "8", "--play"],
        4,
    );
    assert!(stdout.lines().any(|l| l.starts_with("viewer: 4 frames")), "{stdout}");
    assert!(drawn > 0.05, "only {drawn} of the pixels drawn");
}

#[test]
fn the_spectral_viewer_shows_cut_planes() {
    let x = Xvfb::start();
    let (_, drawn) = run_spectral_viewer(
        &x,
        "cut",
        &["--generate", "shell", "--order", "3", "--cut", "z=0.5", "--cut", "x=0.6"],
        3,
    );
    assert!(drawn > 0.025, "only {drawn} of the pixels drawn");
}

/// Runs `galerkin radiosity view SCENE` sweeping the parameters for 4 frames at 320×200 and
/// returns its summary line and the share of the screenshot's pixels drawn (not background).
fn run_radiosity_viewer(x: &Xvfb, scene: &Path, shot: &Path) -> (String, f64) {
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["--validation", "radiosity", "view"])
        .arg(scene)
        .args(["--play", "--quit-after", "4", "--size", "320x200", "--screenshot"])
        .arg(shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(out.status.success(), "galerkin radiosity view failed: {}", String::from_utf8_lossy(&out.stderr));
    let (w, h, rgba) = read_png_rgba8(shot).unwrap();
    assert_eq!((w, h), (320, 200));
    let drawn = drawn_pixels(&rgba);
    (String::from_utf8_lossy(&out.stdout).into_owned(), drawn as f64 / f64::from(w * h))
}

/// The radiosity viewer solves while the parameters sweep (full radiosity: no trained model
/// needed) and fills the window with the room.
#[test]
fn the_radiosity_viewer_sweeps_the_parameters() {
    let x = Xvfb::start();
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let (stdout, drawn) = run_radiosity_viewer(&x, &scene, &dir.join("shot.png"));
    assert!(stdout.contains("radiosity: 496 faces, full mode"), "{stdout}");
    // From inside the living room every pixel sees a wall, the floor or the ceiling.
    assert!(drawn > 0.99, "only {drawn} of the pixels drawn");
}

/// A user's OBJ scene in the radiosity viewer: its deformation target sweeps, the camera is
/// fitted outside its bounds, the box fills part of the window.
#[test]
fn the_radiosity_viewer_shows_an_obj_scene() {
    let x = Xvfb::start();
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = common::obj_box::write_scene(&dir, common::obj_box::SCENE, &common::obj_box::box_obj(1.5));
    let (stdout, drawn) = run_radiosity_viewer(&x, &scene, &dir.join("shot.png"));
    assert!(stdout.contains("full mode") && stdout.contains("at stretch="), "{stdout}");
    // Seen from outside: the box covers part of the window, not all of it.
    assert!((0.05..0.95).contains(&drawn), "{drawn} of the pixels drawn");
}

/// The fluid viewer steps the small tunnel and draws particles over it.
#[test]
fn the_fluid_viewer_plays_the_tunnel() {
    let x = Xvfb::start();
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let shot = dir.join("shot.png");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["--validation", "fluid", "view"])
        .arg(&scene)
        .args(["--play", "--quit-after", "5", "--size", "360x120", "--particles", "2000", "--screenshot"])
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "galerkin fluid view failed: {}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("2000 particles, stopped at frame"), "{stdout}");
    let (w, h, rgba) = read_png_rgba8(&shot).unwrap();
    assert_eq!((w, h), (360, 120));
    let drawn = drawn_pixels(&rgba);
    // The tunnel (aspect 4:1 in a 3:1 window) covers most of the window, minus the obstacle.
    assert!(drawn as f64 > 0.6 * f64::from(w * h), "only {drawn} of {} pixels drawn", w * h);
}

/// The fluid viewer plays a reduced model (trained here on two small tunnel runs), its state
/// lifted for the cells and the device particles, and stops at the frame asked for.
#[test]
fn the_fluid_viewer_plays_a_reduced_model() {
    let x = Xvfb::start();
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let bin = env!("CARGO_BIN_EXE_galerkin");
    let mut runs = Vec::new();
    for scale in ["0.6", "1.4"] {
        let text = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml"),
        )
        .unwrap()
        .replace("scale = 1.0", &format!("scale = {scale}"));
        let scene = dir.join(format!("tunnel-{scale}.toml"));
        std::fs::write(&scene, text).unwrap();
        let run = dir.join(format!("run-{scale}"));
        let out = Command::new(bin)
            .args(["fluid", "simulate"])
            .arg(&scene)
            .args(["--frames", "12", "--force", "--out"])
            .arg(&run)
            .output()
            .unwrap();
        assert!(out.status.success(), "simulate: {}", String::from_utf8_lossy(&out.stderr));
        runs.push(run);
    }
    let model = dir.join("model.safetensors");
    let out =
        Command::new(bin).args(["fluid", "train"]).args(&runs).arg("--out").arg(&model).output().unwrap();
    assert!(out.status.success(), "train: {}", String::from_utf8_lossy(&out.stderr));
    let shot = dir.join("shot.png");
    let out = Command::new(bin)
        .args(["--validation", "fluid", "view", "--model"])
        .arg(&model)
        .args([
            "--motion",
            "replay:1",
            "--play",
            "--quit-after",
            "5",
            "--size",
            "360x120",
            "--particles",
            "1000",
        ])
        .arg("--screenshot")
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "galerkin fluid view --model failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("1000 particles, stopped at frame"), "{stdout}");
    let (w, h, rgba) = read_png_rgba8(&shot).unwrap();
    let drawn = drawn_pixels(&rgba);
    assert!(drawn as f64 > 0.6 * f64::from(w * h), "only {drawn} of {} pixels drawn", w * h);
}

/// A small cavity model (the three single-cavity runs of the small cavity, a few frames each)
/// trained by `fluid train-scene`, for the cavity viewer's tests.
fn small_cavity_model(dir: &Path) -> std::path::PathBuf {
    let model = dir.join("cavity.safetensors");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["fluid", "train-scene", "scenes/fluid/cavity_small.toml", "--frames", "4", "--runs", "0,1,2"])
        .args(["--m-f", "6", "--m-u", "8", "--m-g", "5", "--m-h", "6", "--out"])
        .arg(&model)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success(), "train-scene: {}", String::from_utf8_lossy(&out.stderr));
    model
}

/// The cavity viewer's keys, without a window: 1–3 compress and release, space pauses, r
/// resets; the compressions move towards their targets a little per frame.
#[test]
fn the_cavity_viewer_compresses_the_cavities_the_keys_choose() {
    use galerkin::fluid::reduced::ReducedFluidModel;
    use galerkin::fluid::viewer_cavity::CavityContent;
    use galerkin::render::viewer::ViewerContent;
    let scratch = tempfile::tempdir().expect("a scratch directory");
    let model = ReducedFluidModel::load(&small_cavity_model(scratch.path())).unwrap();
    let mut content = CavityContent::new(model, 100, (320, 240), false).unwrap();
    assert!(content.key("1") && content.key("3"), "the cavity keys are the content's");
    assert_eq!(content.targets(), [0.5, 0.0, 0.5]);
    for _ in 0..5 {
        content.step().unwrap();
    }
    let a = content.compressions();
    assert!((a[0] - 0.1).abs() < 1e-12 && a[1] == 0.0 && (a[2] - 0.1).abs() < 1e-12, "{a:?}");
    assert!(content.title().contains("compressions 0.10/0.00/0.10"), "{}", content.title());
    assert!(content.state().u.iter().any(|&u| u != 0.0), "the compression moved the fluid");
    // The title carries the unseen-velocity indicator's estimate (the model has its Gram
    // matrices): a finite, non-negative percentage.
    let title = content.title();
    let estimate: f64 = title
        .split("estimated error ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no estimated error in {title}"));
    assert!(estimate.is_finite() && estimate >= 0.0, "{title}");
    assert!(content.key("1"), "pressed again: released");
    assert_eq!(content.targets(), [0.0, 0.0, 0.5]);
    assert!(content.key("r"));
    assert_eq!((content.compressions(), content.targets()), ([0.0; 3], [0.0; 3]));
    assert!(content.state().u.iter().all(|&u| u == 0.0), "reset to rest");
    assert!(!content.title().contains("estimated error"), "the reset starts the estimate again");
    assert!(!content.key("x"), "not a key of the cavity viewer");
}

/// `galerkin fluid view MODEL` on a cavity model under Xvfb, keys scripted: cavities 1 and 3
/// compressed by the keys, the reduced particles drawn over the walls, validation on.
#[test]
fn the_cavity_viewer_runs_a_driven_reduced_cavity() {
    let x = Xvfb::start();
    let scratch = tempfile::tempdir().expect("a scratch directory");
    let model = small_cavity_model(scratch.path());
    let shot = scratch.path().join("shot.png");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["--validation", "fluid", "view"])
        .arg(&model)
        .args([
            "--quit-after",
            "12",
            "--keys",
            "1@1,3@4",
            "--size",
            "320x240",
            "--particles",
            "3000",
            "--screenshot",
        ])
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(out.status.success(), "galerkin fluid view failed: {}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("reduced cavity, 3000 particles, stopped at frame"), "{stdout}");
    // Cavity 1 was pressed before frame 1 and cavity 3 before frame 4; both compress at 0.02 a
    // frame, cavity 2 never.
    let line = stdout.lines().find(|l| l.contains("compressions")).expect("summary");
    let amounts: Vec<f64> = line
        .split("compressions ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .map(|s| s.split('/').filter_map(|x| x.parse().ok()).collect())
        .unwrap_or_default();
    assert_eq!(amounts.len(), 3, "{line}");
    assert!(amounts[0] > amounts[2] && amounts[2] > 0.0 && amounts[1] == 0.0, "{line}");
    let (w, h, rgba) = read_png_rgba8(&shot).unwrap();
    assert_eq!((w, h), (320, 240));
    // The walls (grey shades) cover part of the window, seen from outside; some particles
    // (coloured) are drawn on them.
    let drawn = drawn_pixels(&rgba);
    assert!((0.05..0.95).contains(&(drawn as f64 / f64::from(w * h))), "{drawn} of the pixels drawn");
    let coloured = rgba.chunks(4).filter(|p| p[0].abs_diff(p[1]) > 24 || p[1].abs_diff(p[2]) > 24).count();
    assert!(coloured > 50, "only {coloured} coloured (particle) pixels");
}
