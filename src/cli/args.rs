//! The argument groups every capability shares, flattened into its verbs so that one option
//! means one thing everywhere: image output (`--out`, `--size`), colour maps (`--colormap`,
//! `--range LO,HI`), the viewer (`--view`, `--play`, `--quit-after`, `--screenshot`). Device
//! options (`--device`, `--validation`) are global, on [`crate::Cli`].
//!
//! A verb gives a group's options its own defaults with `mut_arg` (e.g. `out/spectral.png`),
//! so `--help` shows them; values are checked when the arguments are parsed, before any work.

use std::path::PathBuf;

use clap::Args;

/// `--out FILE` for a picture: the format comes from the extension, `.png` or `.exr`, and is
/// checked here, before any work (a typo must not cost a render).
pub fn image_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    if path.is_dir() {
        return Err(format!("{s:?} is a directory: give the image file's name"));
    }
    match ImageFormat::of(&path) {
        Some(_) => Ok(path),
        None => Err(format!("{s:?}: the image format comes from the extension: .png or .exr")),
    }
}

pub use galerkin::picture::ImageFormat;

/// Parses `WIDTHxHEIGHT` (1 to 16384 each).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("{s:?} is not WIDTHxHEIGHT"))?;
    let n = |v: &str| v.trim().parse::<u32>().ok().filter(|&v| (1..=16384).contains(&v));
    match (n(w), n(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("{s:?}: width and height must be 1 to 16384")),
    }
}

/// Parses a colour range `LO,HI`: two finite numbers with LO < HI.
pub fn parse_range(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s.split_once(',').ok_or_else(|| format!("{s:?} is not LO,HI"))?;
    let num = |v: &str| v.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    match (num(lo), num(hi)) {
        (Some(lo), Some(hi)) if lo < hi => Ok((lo, hi)),
        (Some(_), Some(_)) => Err(format!("{s:?}: LO must be below HI")),
        _ => Err(format!("{s:?}: LO and HI must be finite numbers")),
    }
}

/// The most marker particles a command seeds (about 0.5 GB of particle state on the host).
pub const MAX_PARTICLES: usize = 10_000_000;
/// The most frames (or steps, or samples) a command runs: each is a solve.
pub const MAX_FRAMES: usize = 1_000_000;
/// The most spacetime elements generated (streamed to `.gst`: about 50 GB at this count).
pub const MAX_ELEMENTS: usize = 200_000_000;

/// A parser for a count of at most `max` (a typo of 2⁴⁰ must be an argument error, not an
/// allocation that aborts the process).
pub fn count_up_to(max: usize) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |s: &str| match s.trim().parse::<usize>() {
        Ok(n) if n <= max => Ok(n),
        Ok(n) => Err(format!("{n} is over the limit of {max}")),
        Err(_) => Err(format!("{s:?} is not a non-negative whole number")),
    }
}

/// A parser for a polynomial order of a basis: 1 to [`galerkin::spectral::MAX_ORDER`] (seed
/// 002's bases; the shaders keep `MAX_ORDER + 1` values per axis), so `--order 13` is an
/// argument error naming the option's range, not a basis error after loading.
pub fn polynomial_order(s: &str) -> Result<usize, String> {
    let max = galerkin::spectral::MAX_ORDER;
    match s.trim().parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        Ok(n) => Err(format!("{n}: orders run from 1 to {max}")),
        Err(_) => Err(format!("{s:?} is not a whole number from 1 to {max}")),
    }
}

/// A parser for a count of 1 to `max`: for steps of a run whose summary divides by them (0 is
/// an argument error, not a "NaN ms per step").
pub fn count_from_one_up_to(
    max: usize,
) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    let up_to = count_up_to(max);
    move |s: &str| match up_to(s)? {
        0 => Err("0: at least 1".into()),
        n => Ok(n),
    }
}

/// Options that a verb accepts but that do nothing for the input chosen — refused as usage
/// errors (exit 2) instead of ignored: `(verb path, option, what makes it inapplicable)`.
/// An option counts as given when it is on the command line (not a default).
pub fn inapplicable(matches: &clap::ArgMatches) -> Option<String> {
    let mut path = Vec::new();
    let mut m = matches;
    while let Some((name, sub)) = m.subcommand() {
        path.push(name);
        m = sub;
    }
    let given = |id: &str| {
        m.try_contains_id(id).unwrap_or(false)
            && m.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
    };
    let file = m.try_contains_id("file").unwrap_or(false)
        && m.try_get_one::<std::path::PathBuf>("file").ok().flatten().is_some();
    let generating: &[&str] = match path.as_slice() {
        ["spectral", "render" | "view"] => &["generate", "order", "geometry_order", "nodes"],
        ["spacetime", "render" | "view"] => &["generate", "elements"],
        _ => &[],
    };
    if file {
        if let Some(id) = generating.iter().find(|id| given(id)) {
            return Some(format!(
                "--{} applies to a generated data set (without FILE); a file brings its own",
                id.replace('_', "-")
            ));
        }
    }
    let viewing =
        matches!(path.as_slice(), [_, "view"]) || m.try_get_one::<bool>("view").ok().flatten() == Some(&true);
    if let Some(id) = ["outline", "axes"].iter().find(|id| viewing && given(id)) {
        return Some(format!("--{id} is drawn over pictures (render); the viewer does not draw it"));
    }
    if let Some(id) = ["camera", "fit"].iter().find(|id| viewing && given(id)) {
        return Some(format!("--{id} sets a picture's camera; in the viewer the arrow keys and +/- move it"));
    }
    if matches!(path.as_slice(), ["radiosity", "render"]) && given("viewpoint") {
        if let Some(id) = ["camera", "fit"].iter().find(|id| given(id)) {
            return Some(format!("--{id} and --viewpoint both place the camera; give one"));
        }
    }
    if viewing && matches!(path.as_slice(), ["radiosity", _]) && given("lights") {
        return Some(
            "--lights applies to pictures; the viewer takes the scene's (or the model's) lighting".into(),
        );
    }
    if viewing && matches!(path.as_slice(), ["spacetime", _]) && given("expr") {
        return Some("--expr is drawn by `spacetime render`; the viewer shows U".into());
    }
    if matches!(path.as_slice(), ["spacetime", "render" | "view"])
        && !file
        && m.try_get_one::<String>("generate").ok().flatten().is_some_and(|g| g == "bar1d")
        && given("elements")
    {
        return Some(
            "--elements: bar1d is the seed's fixed 1D bar (its triangles are given), it has no element count"
                .into(),
        );
    }
    None
}

/// A parser for a positive finite number (an exposure, a scale): 0, negatives, NaN and
/// infinities are argument errors.
pub fn positive_number(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(v) => Err(format!("{v}: give a positive number")),
        Err(_) => Err(format!("{s:?} is not a number")),
    }
}

/// A fraction in [0, 1] (clap value parser).
pub fn fraction(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("`{s}` is not a number"))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not a fraction from 0 to 1"))
    }
}

/// A parser for `A,B,C,D`: exactly four counts (comma-separated), e.g. basis sizes
/// m_u,m_f,m_g,m_h.
pub fn four_counts(s: &str) -> Result<[usize; 4], String> {
    let v: Vec<usize> = s
        .split(',')
        .map(|p| p.trim().parse::<usize>().map_err(|_| format!("{p:?} is not a whole number")))
        .collect::<Result<_, _>>()?;
    <[usize; 4]>::try_from(v).map_err(|v| format!("{s:?}: four numbers, not {}", v.len()))
}

/// A `.vtu` output path (the only format `spectral gen` writes).
pub fn vtu_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    match p.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("vtu") => Ok(p),
        _ => Err(format!("{s:?}: the output is a VTK .vtu file (give NAME.vtu)")),
    }
}

/// Image output: where the picture goes and how large it is.
#[derive(Args, Clone, Debug)]
pub struct ImageArgs {
    /// Output image; its format comes from the extension: .png or .exr (checked before any
    /// work). The verb's description says what each holds.
    #[arg(long, required = false, value_parser = image_path)]
    pub out: PathBuf,
    /// Image size, WIDTHxHEIGHT [default: 1280x720, the same for every picture and window].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
}

impl ImageArgs {
    /// The size asked, or [`galerkin::picture::DEFAULT_SIZE`].
    pub fn size(&self) -> (u32, u32) {
        self.size.unwrap_or(galerkin::picture::DEFAULT_SIZE)
    }
}

/// Where a picture's camera stands, shared by every `render` of a 3D view: `--camera
/// AZ,EL[,DIST]` ([`galerkin::render::Orbit`]) and `--fit`.
#[derive(Args, Clone, Debug)]
pub struct CameraArgs {
    /// The camera's direction and distance, AZ,EL[,DIST]: azimuth in degrees from +x towards
    /// +y, elevation in degrees above the x–y plane (z up, ±89 at most), distance as a multiple
    /// of the fitted one (default 1). Default: fitted, from above the x–y diagonal.
    #[arg(long, value_name = "AZ,EL[,DIST]", value_parser = galerkin::render::Orbit::parse, allow_hyphen_values = true)]
    pub camera: Option<galerkin::render::Orbit>,
    /// Fit the camera tightly: the closest distance at which every corner of the data's
    /// bounding box lies inside the picture (instead of the bounding sphere's, which leaves a
    /// margin that depends on the shape); with --camera, from its direction.
    #[arg(long)]
    pub fit: bool,
}

impl CameraArgs {
    /// The orbit asked for a picture of `size`: `--camera` (tightened by `--fit`), the default
    /// direction tightened by `--fit` alone, or `None` for the renderer's own default camera.
    pub fn orbit(&self, size: (u32, u32)) -> Option<galerkin::render::Orbit> {
        let aspect = f64::from(size.0) / f64::from(size.1.max(1));
        match (self.camera, self.fit) {
            (Some(o), fit) => Some(galerkin::render::Orbit { tight_aspect: fit.then_some(aspect), ..o }),
            (None, true) => Some(galerkin::render::Orbit {
                tight_aspect: Some(aspect),
                ..galerkin::render::Orbit::default_view()
            }),
            (None, false) => None,
        }
    }
}

/// What a PNG picture shows besides the data (every `render`): `--outline`, `--axes`.
#[derive(Args, Clone, Debug)]
pub struct OverlayArgs {
    /// Draw the edges of the data's bounding box over the picture (a planar view: its
    /// rectangle). PNG only.
    #[arg(long)]
    pub outline: bool,
    /// Draw an axis triad in the picture's lower left corner: where +x (red), +y (green) and
    /// +z (blue) point. PNG only.
    #[arg(long)]
    pub axes: bool,
}

impl OverlayArgs {
    /// The overlay asked for.
    pub fn overlay(&self) -> galerkin::picture::Overlay {
        galerkin::picture::Overlay { outline: self.outline, axes: self.axes }
    }
}

/// Colour mapping of a scalar field.
#[derive(Args, Clone, Debug)]
pub struct ColourArgs {
    /// Colour map: viridis, cool-warm, grey, or a ramp PNG file (its first row, left to right).
    #[arg(long, default_value = "viridis", value_name = "NAME|FILE")]
    pub colormap: String,
    /// Colour range (default: the field's range) — narrow it to look at one region in detail.
    #[arg(long, value_name = "LO,HI", value_parser = parse_range, allow_hyphen_values = true)]
    pub range: Option<(f64, f64)>,
}

/// The interactive viewer: a window instead of a file, and scripted runs for tests.
#[derive(Args, Clone, Debug)]
pub struct ViewerArgs {
    /// Open the interactive viewer instead of writing an image (the `view` verb implies it).
    #[arg(long)]
    pub view: bool,
    /// Start playing (time steps, a motion or a sweep — the verb's description says which).
    #[arg(long)]
    pub play: bool,
    /// Quit after presenting this many frames (scripted runs and tests), saving --screenshot.
    #[arg(long, value_name = "FRAMES")]
    pub quit_after: Option<u64>,
    /// Where S (and a scripted run's last frame) saves the screenshot.
    #[arg(long, default_value = "out/screenshot.png", value_parser = screenshot_path)]
    pub screenshot: PathBuf,
}

/// A screenshot is a PNG.
fn screenshot_path(s: &str) -> Result<PathBuf, String> {
    match ImageFormat::of(std::path::Path::new(s)) {
        Some(ImageFormat::Png) => Ok(PathBuf::from(s)),
        _ => Err(format!("{s:?}: screenshots are PNG files (.png)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_paths_are_png_or_exr_by_extension() {
        assert!(image_path("out/a.png").is_ok());
        assert!(image_path("out/a.EXR").is_ok());
        assert!(image_path("out/a.txt").is_err());
        assert!(image_path("out/a").is_err());
        assert_eq!(ImageFormat::of(std::path::Path::new("x.Png")), Some(ImageFormat::Png));
    }

    #[test]
    fn ranges_need_two_ordered_finite_numbers() {
        assert_eq!(parse_range("-1,2.5"), Ok((-1.0, 2.5)));
        assert!(parse_range("2,1").is_err());
        assert!(parse_range("1,1").is_err());
        assert!(parse_range("0,inf").is_err());
        assert!(parse_range("NaN,1").is_err());
        assert!(parse_range("1 2").is_err());
    }

    #[test]
    fn counts_are_bounded() {
        let parse = count_up_to(10);
        assert_eq!(parse("10"), Ok(10));
        assert!(parse("11").unwrap_err().contains("limit of 10"));
        assert!(parse("1099511627776").is_err());
        assert!(parse("-1").is_err());
    }

    #[test]
    fn sizes_are_bounded() {
        assert_eq!(parse_size("640x480"), Ok((640, 480)));
        assert!(parse_size("0x480").is_err());
        assert!(parse_size("16385x2").is_err());
        assert!(parse_size("640").is_err());
    }
}
