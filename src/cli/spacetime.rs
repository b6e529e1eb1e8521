//! `galerkin spacetime render|view|gen|convert|bench`: render a time slice of a spacetime DG
//! data set (seed 003), generate data sets, convert between the `.gst` binary and VTK `.vtu`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::render::Colormap;
use galerkin::spacetime::{dataset, picture, SpacetimeData, SpacetimeView};

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
        mut_arg("out", |a| a.default_value("out/spacetime.png"))
    )]
    Render(RenderArgs),
    /// Open the interactive viewer: space plays/pauses t, `.`/`,` step, `]`/`[` speed ×2/÷2,
    /// h height, e edges, v per-vertex colour, d subdivision, arrows orbit, +/- zoom, S
    /// screenshot, Esc quits.
    #[command(
        mut_arg("out", |a| a.default_value("out/spacetime.png").hide(true)),
        mut_arg("size", |a| a.help("Window size, WIDTHxHEIGHT [default: 1280x720]"))
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
    match dataset::format_of(Path::new(s)) {
        Some(_) => Ok(PathBuf::from(s)),
        None => Err(format!("{s:?}: spacetime data sets are .gst or .vtu files")),
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
    #[arg(long, default_value = "pulses", value_parser = clap::builder::PossibleValuesParser::new(galerkin::spacetime::dataset::RENDERABLE))]
    pub generate: String,
    /// Without FILE: about this many tetrahedra (built in memory: at most 50,000,000).
    #[arg(long, default_value_t = 60_000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_ELEMENTS))]
    pub elements: usize,
    /// The camera (--camera, --fit; the slice plane is the x–y plane). Default: above and in
    /// front (from −y).
    #[command(flatten)]
    pub view_from: crate::cli::args::CameraArgs,
    /// The outline and axis triad (--outline, --axes).
    #[command(flatten)]
    pub overlay: crate::cli::args::OverlayArgs,
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
    /// Colour by a derived field instead of U, evaluated per pixel from each element's exact
    /// polynomials, on a linear ramp over --range (default: the slice's own). Names: speed
    /// (|v|; grad(speed) is its exact gradient), U, v and disp (velocity and displacement
    /// vectors: .x .y, length, dot), eps_xx eps_yy eps_xy (strain), x y (the point), t; + - *
    /// /, abs sqrt log exp sin cos pow min max clamp. E.g. 'eps_xx + eps_yy' (volumetric
    /// strain), 'length(grad(speed))'. Needs the `runtime-shaderc` build feature.
    #[arg(long, value_name = "EXPR")]
    pub expr: Option<String>,
    /// With --expr: the colour range LO,HI of the derived field.
    #[arg(long, value_name = "LO,HI", value_parser = crate::cli::args::parse_range, requires = "expr")]
    pub range: Option<(f64, f64)>,
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
    #[arg(long, default_value = "pulses", value_parser = clap::builder::PossibleValuesParser::new(galerkin::spacetime::dataset::DATA_SETS))]
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

/// `galerkin spacetime gen` ([`dataset::generate_file`]).
pub fn generate_file(args: &GenArgs) -> Result<()> {
    let bar = crate::progress_bar(args.elements as u64, &format!("generating {}", args.generate));
    let written =
        dataset::generate_file(&args.generate, args.elements, &args.out, &mut |done| bar.set_position(done));
    bar.finish_and_clear();
    let w = written?;
    println!(
        "{}: {} elements, {:.1} MB, {:.1} s (fields are analytic, L2-projected per element — not solved)",
        args.out.display(),
        w.elements,
        w.bytes as f64 / 1e6,
        w.seconds
    );
    Ok(())
}

/// `galerkin spacetime convert` ([`dataset::convert`]).
pub fn convert(args: &ConvertArgs) -> Result<()> {
    let w = dataset::convert(&args.input, &args.output)?;
    println!("{} → {}: {} elements", args.input.display(), args.output.display(), w.elements);
    Ok(())
}

/// `galerkin spacetime render` ([`galerkin::spacetime::picture::write_slice`]).
pub fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    if args.file.is_none() && args.generate == "bar1d" {
        return render_bar(desc, args);
    }
    let opened = Instant::now();
    let data = match &args.file {
        Some(path) => dataset::load(path)?,
        None => dataset::generated(&args.generate, args.elements)?,
    };
    let [t0, t1] = data.summary().time;
    let time = args.time.unwrap_or(0.5 * (t0 + t1));
    let view = SpacetimeView {
        height: !args.flat,
        height_scale: args.height_scale,
        edges: !args.no_edges,
        subdivide: args.subdivide,
        u_max: args.umax,
        per_vertex: args.per_vertex,
        ..SpacetimeView::looking_at(data.summary(), time)
    };
    let view = match args.view_from.orbit(args.image.size()) {
        Some(orbit) => SpacetimeView { camera: view.orbit(data.summary(), orbit), ..view },
        None => view,
    };
    picture::check_view(&data, &view)?;
    let derived = match &args.expr {
        Some(text) => Some((
            std::sync::Arc::new(galerkin::expression::spacetime::SpacetimeExpression::new(text)?),
            args.range,
        )),
        None => None,
    };
    if args.viewer.view {
        return open_viewer(desc, data, view, args);
    }
    let elements = data.len();
    let open_ms = opened.elapsed().as_secs_f64() * 1e3;
    let gpu = Gpu::new(desc)?;
    let colormap = Colormap::by_name(&args.colormap)?;
    let out = &args.image.out;
    let source = args
        .file
        .as_ref()
        .map_or_else(|| format!("generated {}", args.generate), |f| f.display().to_string());
    let title = match &args.expr {
        Some(text) => format!("{source}: {text}, t = {time:.4}"),
        None => format!("{source}: t = {time:.4}"),
    };
    let title = (!args.no_legend).then_some(title.as_str());
    let size = args.image.size();
    let decor = galerkin::picture::Decor { title, overlay: args.overlay.overlay() };
    let r = picture::write_slice(&gpu, data, &view, &colormap, (size, out), decor, derived)?;
    println!(
        "spacetime: {elements} elements, t = {time:.4}: {} active ({} streamed to the device), {} triangles, {} edge lines; load {open_ms:.1} ms, slice {:.1} ms, render + readback {:.1} ms, peak RSS {} → {}",
        r.stats.active,
        r.stats.streamed,
        r.stats.triangles,
        r.stats.lines,
        r.slice_ms,
        r.render_ms,
        galerkin::process::peak_memory_mb().map_or("unknown".into(), |mb| format!("{mb:.0} MB")),
        out.display()
    );
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
    #[arg(long, default_value = "pulses", value_parser = clap::builder::PossibleValuesParser::new(galerkin::spacetime::dataset::DATA_SETS))]
    pub generate: String,
    /// Only these data-set sizes (comma-separated element counts), no out-of-core run: for
    /// A/B runs at one size, e.g. `--elements 5000000 --frames 21`.
    #[arg(long, value_delimiter = ',', value_name = "N")]
    pub elements: Vec<usize>,
}

/// `galerkin spacetime bench` ([`galerkin::bench::spacetime::report`]).
pub fn bench(desc: &GpuDesc, args: &BenchArgs) -> Result<()> {
    use galerkin::bench::spacetime::{report, SpacetimeBench};
    let exe = std::env::current_exe().context("finding this executable")?;
    let mut bench = SpacetimeBench::new(args.quick, &args.data_dir, Some(&exe));
    bench.frames = args.frames;
    bench.data_set = args.generate.clone();
    if !args.elements.is_empty() {
        bench.sizes = args.elements.clone();
    }
    if !args.elements.is_empty() || args.generate != "pulses" {
        bench.out_of_core = None;
    }
    let gpu = Gpu::new(desc)?;
    let bar = crate::cli::progress::spinner();
    let result = report(
        &gpu,
        &bench,
        &mut |done| bar.set_message(format!("generating a data set: {done} elements")),
        &mut |s| bar.suspend(|| print!("{s}")),
    );
    bar.finish_and_clear();
    drop(gpu);
    result
}

/// `galerkin spacetime render --generate bar1d` ([`picture::write_bar`]): seed 003's Fig. 3.
fn render_bar(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    let colormap = Colormap::by_name(&args.colormap)?;
    let out = &args.image.out;
    let size = args.image.size();
    let r = picture::write_bar(&gpu, args.elements, &colormap, args.umax, args.per_vertex, size, out)?;
    println!(
        "bar1d (seed 003 Fig. 3): {} triangles over x ∈ [0, 1], t ∈ [{:.3}, {:.3}], U_max {:.3e}, {} → {}",
        r.triangles,
        r.time[0],
        r.time[1],
        r.u_max,
        if args.per_vertex { "per-vertex colour" } else { "per-pixel colour" },
        out.display()
    );
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
        args.image.size(),
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
