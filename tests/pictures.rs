//! Every `render` of a scalar field writes its picture with a title above it and a colour bar
//! beside it (issue "What a new user meets"): the PNG is the asked width plus the legend's
//! panel, at least the asked height plus the title strip, and the bar's panel shows both ends
//! of the colour map; `--no-legend` gives the bare picture.

use std::path::Path;
use std::process::Command;

use galerkin::plot::{BAR_WIDTH, TITLE_HEIGHT};

fn galerkin(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran galerkin");
    assert!(out.status.success(), "galerkin {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// The PNG at `path` is `size` plus the legend, and its bar panel (right of the picture)
/// holds viridis's two ends.
fn has_colour_bar(path: &Path, size: (u32, u32)) {
    let (w, h, rgba) = galerkin::render::read_png_rgba8(path).expect("a PNG");
    // A short picture gets a taller canvas, so that the bar stays readable.
    assert!(w == size.0 + BAR_WIDTH && h >= size.1 + TITLE_HEIGHT, "{}: {w}x{h}", path.display());
    let map = galerkin::render::Colormap::by_name("viridis").expect("viridis");
    let panel: Vec<[u8; 3]> = (0..h)
        .flat_map(|y| (size.0..w).map(move |x| (y, x)))
        .map(|(y, x)| {
            let p = 4 * (y * w + x) as usize;
            [rgba[p], rgba[p + 1], rgba[p + 2]]
        })
        .collect();
    for t in [0.0f64, 1.0] {
        let c = map.sample((t + 0.5 / 256.0).min(1.0 - 0.5 / 256.0));
        let want = [(255.0 * c[0]) as u8, (255.0 * c[1]) as u8, (255.0 * c[2]) as u8];
        // Within 8 of 255 per channel: a bar shorter than the map's 256 steps draws some steps
        // over others, so the very end may be its neighbour (viridis moves < 4 a step).
        let near = |p: &[u8; 3]| (0..3).all(|c| p[c].abs_diff(want[c]) <= 8);
        assert!(panel.iter().any(near), "{}: end {t} of the map is not in the bar", path.display());
    }
}

/// The PNG at `path` is `size` plus the legend, and its bar panel holds the tone map's grey
/// ramp: a column whose greys rise (or fall) steadily from near black to near white over at
/// least 100 rows (text in the panel has no such run).
fn has_grey_ramp(path: &Path, size: (u32, u32)) {
    let (w, h, rgba) = galerkin::render::read_png_rgba8(path).expect("a PNG");
    assert!(w == size.0 + BAR_WIDTH && h >= size.1 + TITLE_HEIGHT, "{}: {w}x{h}", path.display());
    let grey = |x: u32, y: u32| {
        let p = 4 * (y * w + x) as usize;
        (rgba[p] == rgba[p + 1] && rgba[p + 1] == rgba[p + 2]).then_some(rgba[p])
    };
    let ramp = (size.0..w).any(|x| {
        let column: Vec<Option<u8>> = (0..h).map(|y| grey(x, y)).collect();
        // The longest run of greys that never step back, and the span of levels it covers.
        let mut best = (0usize, 0u8, 0u8);
        for dir in [1i16, -1] {
            let mut start = 0;
            for y in 1..=column.len() {
                let ok = y < column.len()
                    && matches!((column[y - 1], column[y]), (Some(a), Some(b)) if dir * (i16::from(b) - i16::from(a)) >= 0);
                if !ok {
                    let run: Vec<u8> = column[start..y].iter().flatten().copied().collect();
                    if run.len() > best.0 {
                        best = (run.len(), *run.iter().min().unwrap_or(&0), *run.iter().max().unwrap_or(&0));
                    }
                    start = y;
                }
            }
        }
        best.0 >= 100 && best.1 <= 16 && best.2 >= 230
    });
    assert!(ramp, "{}: no grey ramp from black to white in the bar panel", path.display());
}

#[test]
fn every_scalar_render_has_a_title_and_a_colour_bar() {
    let dir = tempfile::Builder::new().prefix("galerkin-pictures-").tempdir().expect("scratch");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let tunnel = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    galerkin(&["fluid", "simulate", &tunnel.to_string_lossy(), "--frames", "2", "--out", &out("run")]);
    for (args, size) in [
        (
            vec!["fluid", "render", &out("run"), "--cells", "--size", "320x100", "--out", &out("fluid.png")],
            (320, 100),
        ),
        (vec!["spectral", "render", "--size", "200x160", "--out", &out("spectral.png")], (200, 160)),
        (
            vec![
                "spacetime",
                "render",
                "--elements",
                "2000",
                "--size",
                "200x160",
                "--out",
                &out("spacetime.png"),
            ],
            (200, 160),
        ),
    ] {
        galerkin(&args);
        has_colour_bar(Path::new(args[args.len() - 1]), size);
    }
    // Radiosity: a tone-mapped radiance picture, its bar the tone map's radiance scale.
    let rooms = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    galerkin(&[
        "radiosity",
        "render",
        &rooms.to_string_lossy(),
        "--near-field",
        "centroid",
        "--size",
        "200x160",
        "--out",
        &out("radiosity.png"),
    ]);
    has_grey_ramp(Path::new(&out("radiosity.png")), (200, 160));
    galerkin(&[
        "fluid",
        "render",
        &out("run"),
        "--size",
        "320x100",
        "--no-legend",
        "--out",
        &out("bare.png"),
    ]);
    let (w, h, _) = galerkin::render::read_png_rgba8(Path::new(&out("bare.png"))).expect("a PNG");
    assert_eq!((w, h), (320, 100));
}

/// `--camera AZ,EL[,DIST]` moves a surface's camera (the picture changes); a planar mesh drawn
/// flat, an elevation of 90° and the viewer refuse it.
#[test]
fn the_camera_of_a_surface_picture_is_the_user_s() {
    let dir = tempfile::Builder::new().prefix("galerkin-pictures-").tempdir().expect("scratch");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let render = |camera: Option<&str>, name: &str| {
        let mut args =
            vec!["spectral", "render", "--generate", "artery", "--order", "2", "--size", "160x120"];
        args.extend(["--no-legend", "--out"]);
        let path = out(name);
        let mut all: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        all.push(path.clone());
        if let Some(c) = camera {
            all.extend(["--camera".to_string(), c.to_string()]);
        }
        let refs: Vec<&str> = all.iter().map(String::as_str).collect();
        galerkin(&refs);
        galerkin::render::read_png_rgba8(Path::new(&path)).expect("a PNG").2
    };
    let default = render(None, "default.png");
    let side = render(Some("0,10,1.5"), "side.png");
    assert_ne!(default, side, "--camera did not move the camera");
    let refused = |args: &[&str], word: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(word), "galerkin {args:?}: {err}");
    };
    refused(
        &["spectral", "render", "--generate", "grid", "--camera", "30,20", "--out", &out("flat.png")],
        "planar",
    );
    refused(
        &["spectral", "render", "--generate", "artery", "--camera", "0,90", "--out", &out("up.png")],
        "elevation",
    );
    refused(&["spectral", "view", "--generate", "artery", "--camera", "0,10"], "--camera");
}

/// Spacetime slices take the same `--camera`.
#[test]
fn a_spacetime_slice_takes_the_camera_too() {
    let dir = tempfile::Builder::new().prefix("galerkin-pictures-").tempdir().expect("scratch");
    let png = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let base = ["spacetime", "render", "--elements", "2000", "--size", "160x120", "--no-legend", "--out"];
    let (a, b) = (png("default.png"), png("orbit.png"));
    galerkin(&[&base[..], &[a.as_str()]].concat());
    galerkin(&[&base[..], &[b.as_str(), "--camera", "-120,35,1.3"]].concat());
    let read = |p: &str| galerkin::render::read_png_rgba8(Path::new(p)).expect("a PNG").2;
    assert_ne!(read(&a), read(&b), "--camera did not move the camera");
}

/// One default picture size across capabilities (`galerkin::picture::DEFAULT_SIZE`): every
/// `render` without `--size` writes a bare picture of that size — a 2D fluid run and a planar
/// mesh are fitted into it.
#[test]
fn every_render_defaults_to_one_size() {
    let dir = tempfile::Builder::new().prefix("galerkin-sizes-").tempdir().expect("scratch");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let tunnel = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    let rooms = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    galerkin(&["fluid", "simulate", &tunnel.to_string_lossy(), "--frames", "1", "--out", &out("run")]);
    let renders: [Vec<String>; 4] = [
        vec!["fluid".into(), "render".into(), out("run"), "--cells".into()],
        vec!["spectral".into(), "render".into()],
        vec!["spacetime".into(), "render".into(), "--elements".into(), "2000".into()],
        vec![
            "radiosity".into(),
            "render".into(),
            rooms.to_string_lossy().into(),
            "--near-field".into(),
            "centroid".into(),
        ],
    ];
    for (k, args) in renders.iter().enumerate() {
        let png = out(&format!("{k}.png"));
        let mut args: Vec<&str> = args.iter().map(String::as_str).collect();
        args.extend(["--no-legend", "--out", &png]);
        galerkin(&args);
        let (w, h, _) = galerkin::render::read_png_rgba8(Path::new(&png)).expect("a PNG");
        assert_eq!((w, h), galerkin::picture::DEFAULT_SIZE, "galerkin {args:?}");
    }
}

/// `--fit` (shared by every render): the tight fit draws the same surface larger than the
/// bounding sphere's fit (more pixels covered) from the same direction, and still whole (no
/// covered pixel on the picture's border); a 2D fluid run refuses a camera, radiosity refuses
/// --camera beside --viewpoint (exit 2), and the viewer refuses --fit.
#[test]
fn fit_tightens_the_camera_and_is_refused_where_it_cannot_apply() {
    let dir = tempfile::Builder::new().prefix("galerkin-fit-").tempdir().expect("scratch");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let (w, h) = (200u32, 150u32);
    let covered = |extra: &[&str], name: &str| {
        let path = out(name);
        let mut args =
            vec!["spectral", "render", "--generate", "artery", "--order", "2", "--size", "200x150"];
        args.extend(extra);
        args.extend(["--no-legend", "--out", &path]);
        galerkin(&args);
        let (_, _, rgba) = galerkin::render::read_png_rgba8(Path::new(&path)).expect("a PNG");
        let background = [rgba[0], rgba[1], rgba[2]];
        let drawn = |x: u32, y: u32| {
            let p = 4 * (y * w + x) as usize;
            [rgba[p], rgba[p + 1], rgba[p + 2]] != background
        };
        let count = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| drawn(x, y)).count();
        let on_border =
            (0..w).any(|x| drawn(x, 1) || drawn(x, h - 2)) || (0..h).any(|y| drawn(1, y) || drawn(w - 2, y));
        (count, on_border)
    };
    let (loose, _) = covered(&["--camera", "20,30"], "loose.png");
    let (tight, border) = covered(&["--camera", "20,30", "--fit"], "tight.png");
    assert!(tight as f64 > 1.3 * loose as f64, "--fit covered {tight} pixels against {loose}");
    assert!(!border, "--fit cut the surface at the picture's border");
    let (alone, _) = covered(&["--fit"], "fit.png");
    assert!(alone > loose, "--fit alone covered {alone} pixels");

    let code = |args: &[&str]| {
        let o = Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran");
        (o.status.code(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let tunnel = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    galerkin(&["fluid", "simulate", &tunnel.to_string_lossy(), "--frames", "1", "--out", &out("run")]);
    let (c, err) = code(&["fluid", "render", &out("run"), "--fit", "--out", &out("f.png")]);
    assert!(c == Some(1) && err.contains("3D runs"), "{c:?} {err}");
    let rooms = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let (c, err) = code(&[
        "radiosity",
        "render",
        &rooms.to_string_lossy(),
        "--viewpoint",
        "bedroom",
        "--camera",
        "0,20",
        "--out",
        &out("r.png"),
    ]);
    assert!(c == Some(2) && err.contains("--viewpoint"), "{c:?} {err}");
    let (c, err) = code(&["spectral", "view", "--generate", "artery", "--fit"]);
    assert!(c == Some(2) && err.contains("--fit"), "{c:?} {err}");
}

/// `--outline --axes` on every render: the picture gains the outline's grey and the triad's
/// red x axis in its lower left corner (absent without them); the viewer refuses them.
#[test]
fn outline_and_axes_are_drawn_over_every_render() {
    let dir = tempfile::Builder::new().prefix("galerkin-overlay-").tempdir().expect("scratch");
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let tunnel = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/tunnel_small.toml");
    let rooms = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    galerkin(&["fluid", "simulate", &tunnel.to_string_lossy(), "--frames", "1", "--out", &out("run")]);
    let (w, h) = (240u32, 180u32);
    let renders: [Vec<String>; 5] = [
        vec!["fluid".into(), "render".into(), out("run"), "--cells".into()],
        vec![
            "spectral".into(),
            "render".into(),
            "--generate".into(),
            "artery".into(),
            "--order".into(),
            "2".into(),
        ],
        vec![
            "spectral".into(),
            "render".into(),
            "--generate".into(),
            "annulus".into(),
            "--order".into(),
            "2".into(),
        ],
        vec!["spacetime".into(), "render".into(), "--elements".into(), "2000".into()],
        vec![
            "radiosity".into(),
            "render".into(),
            rooms.to_string_lossy().into(),
            "--near-field".into(),
            "centroid".into(),
            "--camera".into(),
            "30,40,1.3".into(),
        ],
    ];
    let triad_red = |rgba: &[u8]| {
        (h - 80..h).any(|y| {
            (0..80).any(|x| {
                let p = 4 * (y * w + x) as usize;
                rgba[p] > 180 && rgba[p + 1] < 90 && rgba[p + 2] < 90
            })
        })
    };
    for (k, args) in renders.iter().enumerate() {
        let draw = |extra: &[&str], name: &str| {
            let png = out(name);
            let mut all: Vec<&str> = args.iter().map(String::as_str).collect();
            all.extend(["--size", "240x180", "--no-legend", "--out", &png]);
            all.extend(extra);
            galerkin(&all);
            galerkin::render::read_png_rgba8(Path::new(&png)).expect("a PNG").2
        };
        let plain = draw(&[], &format!("{k}-plain.png"));
        let decorated = draw(&["--outline", "--axes"], &format!("{k}-decorated.png"));
        assert!(!triad_red(&plain) || k == 4, "render {k}: red in the corner without --axes");
        assert!(triad_red(&decorated), "render {k} ({args:?}): no red x axis in the lower left corner");
        let changed = plain.chunks_exact(4).zip(decorated.chunks_exact(4)).filter(|(a, b)| a != b).count();
        assert!(changed > 200, "render {k}: only {changed} pixels changed by --outline --axes");
    }
    let o = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["spectral", "view", "--generate", "artery", "--outline"])
        .output()
        .expect("ran");
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
}
