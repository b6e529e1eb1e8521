//! `galerkin spacetime render|view|gen|convert|bench`: render a time slice of a spacetime DG
//! data set (seed 003), generate data sets, convert between the `.gst` binary and VTK `.vtu`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::cli::args::ImageFormat;
use anyhow::{bail, Context, Result};
use clap::Args;
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::render::{write_png_rgba8, ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spacetime::scenario::{self, Scenario};
use galerkin::spacetime::{generate, gst, vtu, ElementRecord, SpacetimeData, SpacetimeError, SpacetimeView};

/// `galerkin spacetime VERB`.
#[derive(clap::Subcommand)]
pub enum Verb {
    /// Render a time slice of a spacetime DG data set (seed 003): height |v|, colour by strain
    /// energy density on the seed's log ramp, exact per-pixel normals, edge overdraw; to PNG
    /// (lit colour, with a title and a colour legend beside the picture) or EXR (channels U,
    /// speed, normal.x/y/z; NaN where no surface; data only). Reads .gst (memory-mapped,
    /// streamed) and .vtu files, or generates a data set (analytic elastodynamic pulses
    /// projected per element, not solved). With --view, open the viewer instead.
    #[command(
        mut_arg("out", |a| a.default_value("out/spacetime.png")),
        mut_arg("size", |a| a.default_value("1280x720"))
    )]
    Render(RenderArgs),
    /// Open the interactive viewer: space plays/pauses t, `.`/`,` step, `]`/`[` speed ×2/÷2,
    /// h height, e edges, v per-vertex colour, d subdivision, arrows orbit, +/- zoom, S
    /// screenshot, Esc quits.
    #[command(
        mut_arg("out", |a| a.default_value("out/spacetime.png").hide(true)),
        mut_arg("size", |a| a.default_value("1280x720").help("Window size, WIDTHxHEIGHT"))
    )]
    View(RenderArgs),
    /// Generate a spacetime data set to a .gst or .vtu file (analytic fields, not solved).
    Gen(GenArgs),
    /// Convert a spacetime data set between .gst and .vtu.
    Convert(ConvertArgs),
    /// Seed 003's renderer: frame time (wall and per stage: slice, subdivide, draw) at
    /// 1280×720 on generated data sets of 10^5 to 5·10^6 elements, growth with pixels, and the
    /// out-of-core first frame of a 2·10^7-element file (generated on first use into
    /// --data-dir).
    Bench(BenchArgs),
}

/// Runs a `galerkin spacetime` verb.
pub fn run(desc: &GpuDesc, verb: &Verb) -> Result<()> {
    match verb {
        Verb::Render(args) => render(desc, args),
        Verb::View(args) => {
            let mut args = args.clone();
            args.viewer.view = true;
            render(desc, &args)
        }
        Verb::Gen(args) => generate_file(args),
        Verb::Convert(args) => convert(args),
        Verb::Bench(args) => bench(desc, args),
    }
}

/// A spacetime data file: `.gst` or `.vtu`, checked when the arguments are parsed.
fn data_path(s: &str) -> Result<PathBuf, String> {
    match extension(Path::new(s)).as_str() {
        "gst" | "vtu" => Ok(PathBuf::from(s)),
        _ => Err(format!("{s:?}: spacetime data sets are .gst or .vtu files")),
    }
}

/// Arguments of `galerkin spacetime render` and `view`.
#[derive(Args, Clone)]
pub struct RenderArgs {
    /// Data set: a `.gst` file (memory-mapped: only the elements near --time are read) or a
    /// VTK `.vtu` file (read whole). Without it, a data set is generated (--generate).
    #[arg(value_parser = data_path)]
    pub file: Option<PathBuf>,
    /// Without FILE: the generated data set: `pulses` (a pressure and a shear pulse crossing
    /// the unit square; structured mesh) or a scenario of seed 003 on a tent-pitched,
    /// non-conforming mesh: `crack`, `inclusions`, `booster` (see `spacetime gen --help`); or
    /// `bar1d`, the seed's Fig. 3: a 1D bar fixed at its left end over (x, t) triangles, the
    /// whole spacetime shown as one image (x to the right, t upwards; EXR channels U, speed, u
    /// and s, the colour coordinate shown).
    #[arg(long, default_value = "pulses")]
    pub generate: String,
    /// Without FILE: about this many tetrahedra (built in memory: at most 50,000,000).
    #[arg(long, default_value_t = 60_000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_ELEMENTS))]
    pub elements: usize,
    /// Time of the slice (default: the middle of the data set's time span).
    #[arg(long)]
    pub time: Option<f64>,
    /// Flat slice (height field off).
    #[arg(long)]
    pub flat: bool,
    /// Height per unit of |v| (default: a tenth of the domain per the largest |v|).
    #[arg(long)]
    pub height_scale: Option<f64>,
    /// Do not overdraw polygon edges (shows the cracks of seed 003 Fig. 4a).
    #[arg(long)]
    pub no_edges: bool,
    /// Quadrisect slice triangles larger than this area, at most 6 times (seed 003 §4.2.2).
    #[arg(long, value_name = "AREA")]
    pub subdivide: Option<f64>,
    /// U_max of the colour ramp s = log(U+1)/log(U_max+1) (default: the slice's largest U).
    #[arg(long)]
    pub umax: Option<f64>,
    /// Colour at the vertices, interpolated (the seed's per-vertex baseline, Fig. 5a).
    #[arg(long)]
    pub per_vertex: bool,
    /// Colour map: viridis, cool-warm, grey, or a ramp PNG file.
    #[arg(long, default_value = "viridis")]
    pub colormap: String,
    #[command(flatten)]
    pub image: crate::cli::args::ImageArgs,
    /// A PNG of the picture alone (--size exactly), without the title and colour legend.
    #[arg(long)]
    pub no_legend: bool,
    #[command(flatten)]
    pub viewer: crate::cli::args::ViewerArgs,
}

/// Arguments of `galerkin spacetime gen`.
#[derive(Args)]
pub struct GenArgs {
    /// The data set. `pulses`: the unit square, a structured conforming mesh, crossing
    /// pressure and shear pulses. Seed 003's scenarios, on tent-pitched meshes refined near the
    /// wave fronts (non-conforming between time slabs): `crack` (a shock loading a plate with a
    /// crack along half its bottom edge; crack-tip scattering), `inclusions` (a composite with
    /// stiff circular fibres: three materials), `booster` (a sector of a rocket-booster cross
    /// section with a star-shaped bore). All fields are analytic travelling and reflecting
    /// pulses L2-projected per element — not solved.
    #[arg(long, default_value = "pulses")]
    pub generate: String,
    /// About this many tetrahedra (at most 200,000,000 streamed to .gst, 50,000,000 to .vtu,
    /// which is built in memory).
    #[arg(long, default_value_t = 100_000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_ELEMENTS))]
    pub elements: usize,
    /// Output: `.gst` (streamed to disk: any size) or `.vtu` (built in memory).
    #[arg(long, value_parser = data_path)]
    pub out: PathBuf,
}

/// Arguments of `galerkin spacetime convert`.
#[derive(Args)]
pub struct ConvertArgs {
    /// Input `.gst` or `.vtu`.
    #[arg(value_parser = data_path)]
    pub input: PathBuf,
    /// Output `.gst` or `.vtu`.
    #[arg(value_parser = data_path)]
    pub output: PathBuf,
}

fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase()
}

/// Loads `.gst` (mapped) or `.vtu` (read, sorted by lowest time).
pub fn load(path: &Path) -> Result<SpacetimeData, SpacetimeError> {
    match extension(path).as_str() {
        "gst" => gst::open(path),
        "vtu" => {
            let mut mesh = vtu::read(path)?;
            mesh.sort_by_lowest_time();
            SpacetimeData::from_mesh(&mesh).map_err(|e| SpacetimeError::File {
                path: path.to_path_buf(),
                detail: format!("{e} (element numbers after sorting by lowest time)"),
            })
        }
        _ => Err(SpacetimeError::File {
            path: path.to_path_buf(),
            detail: "unknown extension: expected .gst or .vtu".into(),
        }),
    }
}

/// `galerkin spacetime gen`.
/// The most elements a data set built in memory may have (a `.vtu`, a rendered `--generate`).
const MAX_IN_MEMORY: usize = 50_000_000;

pub fn generate_file(args: &GenArgs) -> Result<()> {
    if args.elements == 0 {
        bail!("--elements must be positive");
    }
    if extension(&args.out) == "vtu" && args.elements > MAX_IN_MEMORY {
        bail!(
            "--elements {}: a .vtu is built in memory, at most {MAX_IN_MEMORY} elements; write a .gst (streamed) instead",
            args.elements
        );
    }
    let start = Instant::now();
    if args.generate == "bar1d" {
        bail!("bar1d is a 1D bar over (x, t) triangles, not a tetrahedral data set: render it with `galerkin spacetime render --generate bar1d`");
    }
    if let Ok(scenario) = args.generate.parse::<Scenario>() {
        match extension(&args.out).as_str() {
            "gst" => {
                let mut writer = gst::GstWriter::create(&args.out, &scenario::materials(scenario))?;
                let bar = crate::progress_bar(args.elements as u64, &format!("generating {scenario}"));
                let mut failed: Option<SpacetimeError> = None;
                scenario::generate_streaming(scenario, args.elements, &mut |g| {
                    if failed.is_none() {
                        let r = ElementRecord::new(g.corners, &g.frame, g.material, &g.coefficients);
                        failed = writer.push(&r).err();
                        if writer.len() % 4096 == 0 {
                            bar.set_position(writer.len() as u64);
                        }
                    }
                });
                bar.finish_and_clear();
                if let Some(e) = failed {
                    return Err(e.into());
                }
                let n = writer.len();
                writer.finish()?;
                report(&args.out, n, start);
            }
            "vtu" => {
                let mesh = scenario::generate(scenario, args.elements);
                vtu::write(&args.out, &mesh)?;
                report(&args.out, mesh.tets.len(), start);
            }
            other => bail!("{}: unknown extension {other:?}: expected .gst or .vtu", args.out.display()),
        }
        return Ok(());
    }
    match (args.generate.as_str(), extension(&args.out).as_str()) {
        ("pulses", "gst") => {
            let mut writer = gst::GstWriter::create(&args.out, &[generate::PULSES_MATERIAL])?;
            let bar = crate::progress_bar(args.elements as u64, "generating");
            generate::stream_pulses(args.elements, &mut |r| writer.push(r), &mut |done| {
                bar.set_position(done)
            })?;
            bar.finish_and_clear();
            let n = writer.len();
            writer.finish()?;
            report(&args.out, n, start);
        }
        ("pulses", "vtu") => {
            let mesh = generate::pulses(args.elements);
            vtu::write(&args.out, &mesh)?;
            report(&args.out, mesh.tets.len(), start);
        }
        ("pulses", other) => {
            bail!("{}: unknown extension {other:?}: expected .gst or .vtu", args.out.display())
        }
        (other, _) => bail!("unknown scenario {other:?} (available: pulses, crack, inclusions, booster)"),
    }
    Ok(())
}

fn report(path: &Path, elements: usize, start: Instant) {
    let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    println!(
        "{}: {elements} elements, {:.1} MB, {:.1} s (fields are analytic, L2-projected per element — not solved)",
        path.display(),
        bytes as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
}

/// `galerkin spacetime convert`.
pub fn convert(args: &ConvertArgs) -> Result<()> {
    let data = load(&args.input)?;
    match extension(&args.output).as_str() {
        "gst" => {
            gst::write(&args.output, &data)?;
        }
        "vtu" => {
            let mesh = data.to_mesh();
            vtu::write(&args.output, &mesh)?;
        }
        other => bail!("{}: unknown extension {other:?}: expected .gst or .vtu", args.output.display()),
    }
    println!("{} → {}: {} elements", args.input.display(), args.output.display(), data.len());
    Ok(())
}

/// `galerkin spacetime render`.
pub fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    for (name, v) in
        [("--subdivide", args.subdivide), ("--umax", args.umax), ("--height-scale", args.height_scale)]
    {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
            bail!("{name} must be a positive number, got {v}");
        }
    }
    if args.file.is_none() && args.elements > MAX_IN_MEMORY {
        bail!(
            "--elements {}: a generated data set is built in memory, at most {MAX_IN_MEMORY}; generate a .gst with `galerkin spacetime gen` and render that",
            args.elements
        );
    }
    if args.file.is_none() && args.generate == "bar1d" {
        return render_bar(desc, args);
    }
    let opened = Instant::now();
    let data = match &args.file {
        Some(path) => load(path)?,
        None => match args.generate.as_str() {
            "pulses" => SpacetimeData::from_mesh(&generate::pulses(args.elements))?,
            other => match other.parse::<Scenario>() {
                Ok(scenario) => SpacetimeData::from_mesh(&scenario::generate(scenario, args.elements))?,
                Err(_) => bail!("unknown data set {other:?} (available: pulses, crack, inclusions, booster)"),
            },
        },
    };
    let [t0, t1] = data.summary().time;
    let time = args.time.unwrap_or(0.5 * (t0 + t1));
    if !(t0..=t1).contains(&time) {
        bail!("--time {time} is outside the data set's time span [{t0}, {t1}]");
    }
    let base = SpacetimeView::looking_at(data.summary(), time);
    let mut view = SpacetimeView {
        height: !args.flat,
        height_scale: args.height_scale,
        edges: !args.no_edges,
        subdivide: args.subdivide,
        u_max: args.umax,
        per_vertex: args.per_vertex,
        ..base
    };
    if args.viewer.view {
        return open_viewer(desc, data, view, args);
    }
    let elements = data.len();
    let open_ms = opened.elapsed().as_secs_f64() * 1e3;
    let gpu = Gpu::new(desc)?;
    let colormap = Colormap::by_name(&args.colormap)?;
    let mut renderer = galerkin::spacetime::SpacetimeRenderer::new(&gpu, data, &colormap)?;
    let start = Instant::now();
    let stats = renderer.slice(view.time, view.subdivide)?;
    let slice_ms = start.elapsed().as_secs_f64() * 1e3;
    let (w, h) = args.image.size_or((1280, 720));
    let out = &args.image.out;
    let exr = args.image.format() == ImageFormat::Exr;
    let format = if exr { ColorFormat::Rgba32F } else { ColorFormat::Rgba8 };
    let target = RenderTarget::new(&gpu, "spacetime", w, h, format)?;
    let start = Instant::now();
    // The legend needs the ramp's U_max: resolved once here, and the render uses the same.
    let legend = !exr && !args.no_legend;
    if legend && view.u_max.is_none() {
        view.u_max = Some(renderer.u_max_for(&target, &view)?);
    }
    let pixels = renderer.render(&target, &view)?;
    let draw_ms = start.elapsed().as_secs_f64() * 1e3;
    let pixels = match (legend, pixels, view.u_max) {
        (true, Pixels::Rgba8(rgba), Some(u_max)) if u_max > 0.0 => {
            let bar = galerkin::plot::ColourBar {
                colormap: &colormap,
                range: (1.0, u_max + 1.0),
                log: true,
                label: "U, strain energy density (ramp log(U + 1))",
                shift: 1.0,
            };
            let title = format!(
                "{}: t = {time:.4}",
                args.file
                    .as_ref()
                    .map_or_else(|| format!("generated {}", args.generate), |f| f.display().to_string())
            );
            galerkin::plot::picture_with_colour_bar(&rgba, (w, h), &bar, &title, out)?;
            None
        }
        (_, pixels, _) => Some(pixels),
    };
    // EXR channels: U, |v| and the normal (n_z from the unit length; NaN where no surface).
    let nz =
        |p: &[f32]| if p[2].is_nan() { f32::NAN } else { (1.0 - p[2] * p[2] - p[3] * p[3]).max(0.0).sqrt() };
    if let Some(pixels) = pixels {
        write_image(
            out,
            (w, h),
            pixels,
            &[
                ("U", |p| p[0]),
                ("speed", |p| p[1]),
                ("normal.x", |p| p[2]),
                ("normal.y", |p| p[3]),
                ("normal.z", nz),
            ],
        )?;
    }
    println!(
        "spacetime: {elements} elements, t = {time:.4}: {} active ({} streamed to the device), {} triangles, {} edge lines; load {open_ms:.1} ms, slice {slice_ms:.1} ms, render + readback {draw_ms:.1} ms, peak RSS {} → {}",
        stats.active,
        stats.streamed,
        stats.triangles,
        stats.lines,
        galerkin::process::peak_memory_mb().map_or("unknown".into(), |mb| format!("{mb:.0} MB")),
        out.display()
    );
    drop((target, renderer));
    drop(gpu);
    Ok(())
}

/// Arguments of `galerkin spacetime bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// 10^5 and 10^6 elements only, no out-of-core run (a minute instead of ten).
    #[arg(long)]
    pub quick: bool,
    /// Where the generated data sets are kept between runs (pulses-N.gst; ~1.2 GB for 5·10^6
    /// elements, ~4.9 GB for the 2·10^7-element out-of-core file).
    #[arg(long, default_value = "out/bench-data")]
    pub data_dir: PathBuf,
    /// Frames per configuration (the median is reported).
    #[arg(long, default_value_t = 30, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: usize,
    /// The data sets to generate: `pulses` (structured) or a tent-pitched scenario (`crack`,
    /// `inclusions`, `booster`); the out-of-core file is always `pulses`.
    #[arg(long, default_value = "pulses")]
    pub generate: String,
    /// Only these data-set sizes (comma-separated element counts), no out-of-core run: for
    /// A/B runs at one size, e.g. `--elements 5000000 --frames 21`.
    #[arg(long, value_delimiter = ',', value_name = "N")]
    pub elements: Vec<usize>,
}

/// The data set `scenario` of about `elements` elements in `dir`, generated if missing.
fn bench_data(dir: &Path, scenario: &str, elements: usize) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(format!("{scenario}-{elements}.gst"));
    if gst::open(&path).is_err() {
        generate_file(&GenArgs { generate: scenario.into(), elements, out: path.clone() })?;
    }
    Ok(path)
}

/// `galerkin spacetime bench`: frame times of seed 003's renderer on generated data (the
/// issue's goal: ≥ 30 FPS at 1280×720 on 5·10^6 elements), their growth with active elements
/// and with pixels, and the out-of-core first frame of a 2·10^7-element file.
pub fn bench(desc: &GpuDesc, args: &BenchArgs) -> Result<()> {
    use galerkin::bench::spacetime::{measure_frames, FrameReport};
    if args.frames == 0 {
        bail!("--frames must be positive");
    }
    let sizes: &[usize] = match (args.elements.as_slice(), args.quick) {
        ([], true) => &[100_000, 1_000_000],
        ([], false) => &[100_000, 1_000_000, 5_000_000],
        (chosen, _) => chosen,
    };
    if let Some(&n) = sizes.iter().find(|&&n| n < 1000) {
        bail!("--elements {n}: data sets start at 1000 elements");
    }
    let gpu = Gpu::new(desc)?;
    println!("device: {} ({})", gpu.caps().device_name, gpu.caps().driver);
    let colormap = Colormap::viridis();
    let header = "| elements | active | triangles | size | subdivide | frame (wall) | FPS | slice | subdivide | draw | frames streaming |\n|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|";
    let row = |n: usize, size: (u32, u32), sub: Option<f64>, r: &FrameReport| {
        println!(
            "| {n} | {:.0} | {:.0} | {}×{} | {} | {:.1} ms | {:.1} | {:.2} ms | {:.2} ms | {:.1} ms | {}/{} |",
            r.active,
            r.triangles,
            size.0,
            size.1,
            sub.map_or("off".into(), |a| format!("{a:.1e}")),
            r.wall_ms,
            r.fps(),
            r.slice_ms,
            r.subdivide_ms,
            r.draw_ms,
            r.streaming_frames,
            r.frames
        )
    };
    println!("\nFrames at an advancing t (0.3 → 0.7 of the span), height and edges on, U_max 0.05; medians of {} frames:\n\n{header}", args.frames);
    let mut largest = None;
    for &n in sizes {
        let path = bench_data(&args.data_dir, &args.generate, n)?;
        let data = gst::open(&path)?;
        let [t0, t1] = data.summary().time;
        let view = SpacetimeView { u_max: Some(0.05), ..SpacetimeView::looking_at(data.summary(), t0) };
        let times = [t0 + 0.3 * (t1 - t0), t0 + 0.7 * (t1 - t0)];
        let mut r = galerkin::spacetime::SpacetimeRenderer::new(&gpu, data, &colormap)?;
        let report = measure_frames(&gpu, &mut r, &view, (1280, 720), times, args.frames, 3)?;
        row(n, (1280, 720), None, &report);
        largest = Some((n, r, view, times, report));
    }
    let (n, mut r, view, times, base) = largest.expect("at least one size");
    // Subdivision: triangles larger than the mean slice triangle (over the bounding box) are
    // quadrisected.
    let area = r.data().summary().size().powi(2) / base.triangles.max(1.0);
    let sub = SpacetimeView { subdivide: Some(area), ..view };
    row(n, (1280, 720), Some(area), &measure_frames(&gpu, &mut r, &sub, (1280, 720), times, args.frames, 2)?);
    let no_edges = SpacetimeView { edges: false, ..view };
    let rep = measure_frames(&gpu, &mut r, &no_edges, (1280, 720), times, args.frames, 2)?;
    println!("(the same without edge overdraw: {:.1} ms per frame, draw {:.1} ms)", rep.wall_ms, rep.draw_ms);
    // The floor: the same triangles with nothing evaluated per pixel and no edges — what the
    // slicing and the rasteriser cost by themselves, before any shading.
    let floor = SpacetimeView { unshaded: true, ..no_edges };
    let rep = measure_frames(&gpu, &mut r, &floor, (1280, 720), times, args.frames, 2)?;
    println!(
        "(the floor — one constant colour per pixel, nothing evaluated, no edges: {:.1} ms per frame, slice {:.2} ms, subdivide {:.2} ms, draw {:.1} ms)",
        rep.wall_ms, rep.slice_ms, rep.subdivide_ms, rep.draw_ms
    );
    println!("\nGrowth with pixels ({n} elements):\n\n{header}");
    for size in [(320, 180), (640, 360), (1280, 720), (1920, 1080)] {
        let rep = if size == (1280, 720) {
            base
        } else {
            measure_frames(&gpu, &mut r, &view, size, times, args.frames, 2)?
        };
        row(n, size, None, &rep);
    }
    drop(r);
    drop(gpu);
    if !args.quick && args.elements.is_empty() && args.generate == "pulses" {
        let path = bench_data(&args.data_dir, "pulses", 20_000_000)?;
        println!("\nOut of core: the first frame of {} in a fresh process:", path.display());
        let exe = std::env::current_exe().context("finding this executable")?;
        let start = Instant::now();
        let out = args.data_dir.join("out-of-core.png");
        let status = std::process::Command::new(exe)
            .args([
                "spacetime",
                "render",
                &path.to_string_lossy(),
                "--time",
                "0.2",
                "--umax",
                "0.05",
                "--out",
                &out.to_string_lossy(),
            ])
            .status()
            .context("running the out-of-core frame")?;
        if !status.success() {
            bail!("the out-of-core frame failed ({status})");
        }
        println!("process wall time (Vulkan start-up included): {:.2} s", start.elapsed().as_secs_f64());
    }
    Ok(())
}

/// `galerkin spacetime render --generate bar1d`: seed 003's Fig. 3, the whole (x, t) spacetime of a
/// bar, per pixel (or per vertex with --per-vertex).
fn render_bar(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    use galerkin::spacetime::bar::{bar1d, BarRenderer};
    let mesh = bar1d(args.elements);
    let gpu = Gpu::new(desc)?;
    let mut renderer = BarRenderer::new(&gpu, &mesh, &Colormap::by_name(&args.colormap)?)?;
    let (w, h) = args.image.size_or((1280, 720));
    let out = &args.image.out;
    let exr = args.image.format() == ImageFormat::Exr;
    let u_max = match args.umax {
        Some(u) => u,
        None => {
            // The largest U over the image's pixels, from a data pass.
            let data = RenderTarget::new(&gpu, "bar U_max", w, h, ColorFormat::Rgba32F)?;
            let Pixels::Rgba32F(v) = renderer.render(&data, 1.0, false)? else {
                bail!("float target returned bytes")
            };
            v.chunks_exact(4).map(|p| f64::from(p[0])).filter(|u| u.is_finite()).fold(0.0, f64::max)
        }
    };
    let target =
        RenderTarget::new(&gpu, "bar", w, h, if exr { ColorFormat::Rgba32F } else { ColorFormat::Rgba8 })?;
    let pixels = renderer.render(&target, u_max, args.per_vertex)?;
    write_image(
        out,
        (w, h),
        pixels,
        &[("U", |p| p[0]), ("speed", |p| p[1]), ("u", |p| p[2]), ("s", |p| p[3])],
    )?;
    println!(
        "bar1d (seed 003 Fig. 3): {} triangles over x ∈ [0, 1], t ∈ [{:.3}, {:.3}], U_max {u_max:.3e}, {} → {}",
        mesh.triangles.len(),
        renderer.window()[2],
        renderer.window()[3],
        if args.per_vertex { "per-vertex colour" } else { "per-pixel colour" },
        out.display()
    );
    drop((target, renderer));
    drop(gpu);
    Ok(())
}

#[cfg(feature = "viewer")]
fn open_viewer(desc: &GpuDesc, data: SpacetimeData, view: SpacetimeView, args: &RenderArgs) -> Result<()> {
    use galerkin::render::viewer::{run, ViewOptions};
    let content = galerkin::spacetime::viewer::SpacetimeContent::new(
        data,
        view,
        Colormap::by_name(&args.colormap)?,
        args.image.size_or((1280, 720)),
        args.viewer.play,
    );
    let options = ViewOptions {
        frames: args.viewer.quit_after,
        screenshot: args.viewer.screenshot.clone(),
        ..ViewOptions::default()
    };
    run(desc.clone(), Box::new(content), options)
}

#[cfg(not(feature = "viewer"))]
fn open_viewer(_: &GpuDesc, _: SpacetimeData, _: SpacetimeView, _: &RenderArgs) -> Result<()> {
    bail!("this build has no viewer: rebuild with the default `viewer` feature")
}

/// A pixel channel of an EXR file: its name and its value from a pixel's four floats.
type Channel = (&'static str, fn(&[f32]) -> f32);

/// Writes colour pixels as PNG, float pixels as EXR with `channels`, creating the folder.
fn write_image(out: &Path, (w, h): (u32, u32), pixels: Pixels, channels: &[Channel]) -> Result<()> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    match pixels {
        Pixels::Rgba8(c) => write_png_rgba8(out, w, h, &c)?,
        Pixels::Rgba32F(v) => {
            let named = channels
                .iter()
                .map(|(name, f)| (*name, v.chunks_exact(4).map(f).collect::<Vec<f32>>()))
                .collect();
            galerkin::render::write_exr_channels(out, w, h, named)?;
        }
    }
    Ok(())
}
