//! `galerkin`: the command-line front end. `galerkin demo` runs every capability's demo and
//! writes `out/*.png`; `galerkin info` describes the device; `galerkin view` opens a window;
//! `galerkin bench gpu` measures the device's ceilings next to the CPU.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};

mod cli {
    pub mod fluid;
    pub mod fluid_reduced;
    pub mod full_frames;
    pub mod radiosity;
    pub mod spacetime;
    pub mod spectral;
}
use clap::{Parser, Subcommand};
use galerkin::demo::axpy::{axpy_error_ratio, Axpy};
use galerkin::demo::field::{check_colours, check_values, FieldOutput, FieldPass};
use galerkin::demo::scene::DemoScene;
use galerkin::gpu::{shaders, vk, Buffer, Gpu, GpuDesc, Profiler};
use galerkin::render::{write_exr_rgba, write_png_rgba8, ColorFormat, Colormap, Pixels, RenderTarget};

/// galerkin: reduced simulation by non-polynomial Galerkin projection and pixel-exact
/// rendering of high-order solutions, on Vulkan.
///
/// Environment: GALERKIN_DEVICE=<substring> picks a device by name; GALERKIN_VALIDATION=1
/// turns on the Khronos validation layer; VK_DRIVER_FILES selects Vulkan drivers (e.g.
/// /usr/share/vulkan/icd.d/lvp_icd.json for lavapipe); GALERKIN_LOG=debug shows diagnostics.
#[derive(Parser)]
#[command(version, about, long_about)]
struct Cli {
    /// Use the first device whose name contains this (overrides GALERKIN_DEVICE).
    #[arg(long, global = true, value_name = "SUBSTRING")]
    device: Option<String>,
    /// Enable the Khronos validation layer (same as GALERKIN_VALIDATION=1).
    #[arg(long, global = true)]
    validation: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Describe the device: name, driver, Vulkan version, limits, memory, and compiled shaders.
    Info,
    /// Run the demos, check each against its CPU reference, and write images to --out.
    Demo {
        /// Scene file (TOML).
        #[arg(long, default_value = "scenes/demo.toml")]
        scene: PathBuf,
        /// Output directory.
        #[arg(long, default_value = "out")]
        out: PathBuf,
    },
    /// Open a window showing the demo scene (Esc quits, S saves a screenshot PNG,
    /// arrow keys orbit the camera).
    View {
        /// Scene file (TOML).
        #[arg(long, default_value = "scenes/demo.toml")]
        scene: PathBuf,
        /// Quit after presenting this many frames (for scripted runs and tests).
        #[arg(long)]
        frames: Option<u64>,
        /// Where S saves the screenshot; with --frames, also saved just before quitting.
        #[arg(long, default_value = "out/screenshot.png")]
        screenshot: PathBuf,
        /// With --frames: ask for this window size (WIDTHxHEIGHT) halfway through the run.
        #[arg(long, value_name = "WxH", value_parser = parse_size)]
        resize_to: Option<(u32, u32)>,
    },
    /// Render a time slice of a spacetime DG data set (seed 003): height |v|, colour by strain
    /// energy density on the seed's log ramp, exact per-pixel normals, edge overdraw. Reads
    /// .gst (memory-mapped, streamed) and .vtu files, or generates a data set (the fields are
    /// analytic elastodynamic pulses projected per element, not solved).
    Spacetime(cli::spacetime::RenderArgs),
    /// Generate a spacetime data set to a .gst or .vtu file (analytic fields, not solved).
    SpacetimeGen(cli::spacetime::GenArgs),
    /// Convert a spacetime data set between .gst and .vtu.
    SpacetimeConvert(cli::spacetime::ConvertArgs),
    /// Render spectral elements per pixel (seed 002): a .vtu file of VTK Lagrange cells or a
    /// generated data set, planar or a surface in 3D, to PNG or EXR.
    Spectral(cli::spectral::RenderArgs),
    /// Generate a spectral-element data set to a .vtu file (analytic fields, not solved).
    SpectralGen(cli::spectral::GenArgs),
    /// Radiosity on the deforming two-room scene (seed 000 §8–9): full radiosity of a
    /// configuration, drawn to PNG or EXR.
    Radiosity {
        #[command(subcommand)]
        action: cli::radiosity::Action,
    },
    /// Fluids on deforming simplicial meshes (seed 000 §5–7): simulate a scene in the full
    /// space to a snapshot directory, draw its frames with marker particles.
    Fluid {
        #[command(subcommand)]
        action: cli::fluid::Action,
    },
    /// Benchmarks.
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Seed 003's spacetime renderer: frame time (wall and per stage: slice, subdivide, draw)
    /// at 1280×720 on generated data sets of 10^5 to 5·10^6 elements, growth with pixels, and
    /// the out-of-core first frame of a 2·10^7-element file (generated on first use into
    /// --data-dir).
    Spacetime(cli::spacetime::BenchArgs),
    /// Seed 002's table: FPS of orders 1–8 on the artery (704) and coil (3332) at 1024×768,
    /// per pixel against per vertex in the same run; frame time against pixels and elements.
    Spectral(cli::spectral::BenchArgs),
    /// Full radiosity (seed 000 §8): form factors with visibility and the Jacobi solve of
    /// Eq. 14, on the CPU and the device, for the small and the full two-room scene. The
    /// reduced model's rate is measured by `galerkin radiosity compare`.
    Radiosity(cli::radiosity::BenchArgs),
    /// Full-space fluid (seed 000 §5, Table 1): seconds per step for deformation, advection
    /// and projection on the deforming cavity from 10³ to 3·10⁵ cells next to the paper's,
    /// and particle advection (10,000 particles) on the CPU and the device.
    Fluid(cli::fluid::BenchArgs),
    /// The reduced fluid (seed 000 §6): the reduced step at Table 1's cavity basis sizes
    /// (m_f 64, m_u 128, m_g 5, m_h 16) on synthetic bases of the cavity mesh, stage by stage
    /// with the Krylov and Padé exponentials; and 10⁶ reduced steps of a small tunnel model
    /// watching the energy (trained first into out/bench-fluid-reduced/).
    FluidReduced(cli::fluid_reduced::BenchArgs),
    /// The reduction core: premultiplication of the fluid volume tensor at the paper's cavity
    /// size (88,671 cells, m = 128, m_g = 5) next to faer's GEMM of its final stage, reduced
    /// evaluation per call and per batch, and premultiplication time against cells and m.
    Reduce {
        /// Smaller sizes: seconds instead of a minute or two.
        #[arg(long)]
        quick: bool,
    },
    /// The device's ceilings next to their CPU peers: dispatch overhead, upload/download,
    /// FMA peak, streaming triad, tiled SGEMM (peer: faer). Prints a Markdown table.
    Gpu {
        /// Small sizes: seconds instead of a minute or two.
        #[arg(long)]
        quick: bool,
    },
}

fn main() {
    let filter = tracing_subscriber::EnvFilter::try_from_env("GALERKIN_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn,winit=error"));
    tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

fn desc(cli: &Cli) -> GpuDesc {
    let mut d = GpuDesc::default();
    if let Some(name) = &cli.device {
        d.device_name = Some(name.clone());
    }
    d.validation |= cli.validation;
    d
}

fn run(cli: Cli) -> Result<()> {
    let desc = desc(&cli);
    match cli.command {
        Command::Info => info(&desc),
        Command::Demo { scene, out } => demo(&desc, &scene, &out),
        Command::View { scene, frames, screenshot, resize_to } => {
            view(desc, &scene, frames, screenshot, resize_to)
        }
        Command::Spacetime(args) => cli::spacetime::render(&desc, &args),
        Command::SpacetimeGen(args) => cli::spacetime::generate_file(&args),
        Command::SpacetimeConvert(args) => cli::spacetime::convert(&args),
        Command::Spectral(args) => cli::spectral::render(&desc, &args),
        Command::Radiosity { action } => cli::radiosity::run(&desc, &action),
        Command::Fluid { action } => cli::fluid::run(&desc, &action),
        Command::SpectralGen(args) => cli::spectral::generate_file(&args),
        Command::Bench { what: BenchWhat::Gpu { quick } } => bench_gpu(&desc, quick),
        Command::Bench { what: BenchWhat::Reduce { quick } } => bench_reduce(&desc, quick),
        Command::Bench { what: BenchWhat::Spacetime(args) } => cli::spacetime::bench(&desc, &args),
        Command::Bench { what: BenchWhat::Spectral(args) } => cli::spectral::bench(&desc, &args),
        Command::Bench { what: BenchWhat::Radiosity(args) } => cli::radiosity::bench(&desc, &args),
        Command::Bench { what: BenchWhat::Fluid(args) } => cli::fluid::bench(&desc, &args),
        Command::Bench { what: BenchWhat::FluidReduced(args) } => cli::fluid_reduced::bench(&args),
    }
}

/// A progress bar with an ETA for long work (`what` on the left, a message after the ETA);
/// indicatif hides it when stderr is not a terminal.
pub(crate) fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{what:<28} {{bar:30}} {{pos}}/{{len}} eta {{eta}} {{msg}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// After the work: fail if validation was on and reported errors.
pub(crate) fn check_validation(gpu: Gpu) -> Result<()> {
    let log = gpu.validation_log();
    drop(gpu);
    if let Some(log) = log {
        let errors = log.errors();
        if !errors.is_empty() {
            bail!("{} Vulkan validation error(s); the first: {}", errors.len(), errors[0]);
        }
    }
    Ok(())
}

fn info(desc: &GpuDesc) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    let c = gpu.caps();
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    println!("device        {} ({:?})", c.device_name, c.device_type);
    println!("driver        {}", c.driver);
    println!("vulkan        {}.{}.{}", c.api_version.0, c.api_version.1, c.api_version.2);
    println!("ids           vendor {:#06x} device {:#06x}", c.vendor_id, c.device_id);
    println!("limits");
    println!("  maxStorageBufferRange           {:.0} MiB", mib(c.max_storage_buffer_range));
    println!("  maxMemoryAllocationSize         {:.0} MiB", mib(c.max_memory_allocation_size));
    println!("  maxBufferSize                   {:.0} MiB", mib(c.max_buffer_size.min(1 << 50)));
    println!("  minStorageBufferOffsetAlignment {}", c.min_storage_buffer_offset_alignment);
    println!("  maxComputeWorkGroupCount        {:?}", c.max_compute_work_group_count);
    println!(
        "  maxComputeWorkGroupSize         {:?} ({} invocations)",
        c.max_compute_work_group_size, c.max_compute_work_group_invocations
    );
    println!("  maxComputeSharedMemorySize      {} KiB", c.max_compute_shared_memory_size / 1024);
    println!("  subgroup size                   {}", c.subgroup_size);
    println!("  maxPushConstantsSize            {} B", c.max_push_constants_size);
    println!("  maxImageDimension2D             {}", c.max_image_dimension_2d);
    println!("  maxFragmentInputComponents      {}", c.max_fragment_input_components);
    match c.timestamp_period_ns {
        Some(p) => println!("  timestamps                      {p} ns per tick"),
        None => println!("  timestamps                      not supported"),
    }
    println!(
        "features      shaderFloat64 {}, geometryShader {}, fillModeNonSolid {}",
        c.shader_float64, c.geometry_shader, c.fill_mode_non_solid
    );
    println!("memory heaps");
    for (i, (size, flags)) in c.memory_heaps.iter().enumerate() {
        println!("  {i}: {:.0} MiB {flags:?}", mib(*size));
    }
    println!("memory types");
    for (i, (flags, heap)) in c.memory_types.iter().enumerate() {
        println!("  {i}: heap {heap} {flags:?}");
    }
    println!("shaders ({})", shaders::ALL.len());
    for (name, words) in shaders::ALL {
        println!("  {name:<32} {:>6} words", words.len());
    }
    check_validation(gpu)
}

fn demo(desc: &GpuDesc, scene_path: &Path, out: &Path) -> Result<()> {
    let scene = DemoScene::load(scene_path)?;
    let gpu = Gpu::new(desc)?;
    let caps = gpu.caps();
    println!("device: {} — {}", caps.device_name, caps.driver);

    // Compute: y <- a x + y, every element against the CPU f64 reference.
    let n = usize::try_from(scene.axpy.n).context("axpy.n does not fit in memory")?;
    let a = scene.axpy.a;
    let x: Vec<f32> = (0..n).map(|i| ((i % 1013) as f32 - 506.0) / 506.0).collect();
    let y: Vec<f32> = (0..n).map(|i| ((i % 977) as f32) / 977.0).collect();
    let xb = Buffer::from_slice(&gpu, "demo x", &x, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let yb = Buffer::from_slice(&gpu, "demo y", &y, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let axpy = Axpy::new(&gpu)?;
    let binding = axpy.bind(&gpu, &xb, &yb)?;
    let mut profiler = Profiler::new(&gpu, 1).ok();
    let t = Instant::now();
    gpu.run(|rec| match profiler.as_mut() {
        Some(p) => {
            p.record_reset(rec);
            p.scope(rec, "axpy", |rec| axpy.record(&gpu, rec, &binding, a as f32));
        }
        None => axpy.record(&gpu, rec, &binding, a as f32),
    })?;
    let wall = t.elapsed();
    let kernel_ms = profiler.as_ref().and_then(|p| p.results().ok()).and_then(|r| r.first().map(|s| s.1));
    let result = yb.download(&gpu)?;
    let (ratio, at) = axpy_error_ratio(a, &x, &y, &result);
    println!(
        "axpy: {n} floats in {} binding(s), {} (kernel) / {:.1} ms (submit + wait); worst error {ratio:.2} of the f32 bound at element {at}",
        binding.chunk_count(),
        kernel_ms.map_or("n/a".to_string(), |ms| format!("{ms:.1} ms")),
        wall.as_secs_f64() * 1e3
    );
    if ratio > 1.0 {
        bail!("axpy differs from its CPU reference beyond the f32 bound");
    }
    drop((xb, yb, binding, axpy));

    // Graphics: the field, values (checked, EXR) and colours (checked, PNG).
    let (w, h) = (scene.image.width, scene.image.height);
    let colormap = Colormap::by_name(&scene.colormap_name())?;
    let p = scene.field.coefficients;
    let values = RenderTarget::new(&gpu, "demo field values", w, h, ColorFormat::Rgba32F)?;
    let pass = FieldPass::new(
        &gpu,
        values.render_pass(),
        &p,
        scene.field.tessellation,
        &colormap,
        scene.ramp(),
        FieldOutput::Value,
    )?;
    let Pixels::Rgba32F(v) =
        values.render(&gpu, [0.0; 4], |rec| pass.record(rec, values.extent(), &scene.camera))?
    else {
        bail!("float target returned bytes");
    };
    let check = check_values(&scene.camera, &p, w, h, &v);
    write_exr_rgba(&out.join("field.exr"), w, h, &v)?;
    println!(
        "field values: {w}×{h}, {} covered pixels checked (worst {:.3} of tolerance), {} background, {} on the outline → {}",
        check.checked,
        check.worst,
        check.background,
        check.outline,
        out.join("field.exr").display()
    );
    if !check.passed() {
        bail!(
            "{} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.first_failure.unwrap_or_default()
        );
    }
    let colours = RenderTarget::new(&gpu, "demo field colours", w, h, ColorFormat::Rgba8)?;
    let pass = FieldPass::new(
        &gpu,
        colours.render_pass(),
        &p,
        scene.field.tessellation,
        &colormap,
        scene.ramp(),
        FieldOutput::Colour,
    )?;
    let background = galerkin::render::BACKGROUND;
    let Pixels::Rgba8(c) =
        colours.render(&gpu, background, |rec| pass.record(rec, colours.extent(), &scene.camera))?
    else {
        bail!("RGBA8 target returned floats");
    };
    let bg = background.map(|v| (v * 255.0f32).round() as u8);
    let check = check_colours(&scene.camera, &p, &colormap, scene.ramp(), w, h, &c, bg);
    write_png_rgba8(&out.join("field.png"), w, h, &c)?;
    println!(
        "field colours ({}): {} covered pixels checked (worst {:.3} of tolerance) → {}",
        colormap.name(),
        check.checked,
        check.worst,
        out.join("field.png").display()
    );
    if !check.passed() {
        bail!(
            "{} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.first_failure.unwrap_or_default()
        );
    }
    drop((pass, colours, values));

    // Spacetime DG (seed 003): one lit frame (PNG) and its raw fields (EXR) of generated pulses.
    let mesh = galerkin::spacetime::generate::pulses(20_000);
    let mut renderer = galerkin::spacetime::SpacetimeRenderer::from_mesh(&gpu, &mesh, &colormap)?;
    let t = 0.5 * mesh.time_range().1;
    let view = galerkin::spacetime::SpacetimeView::looking_at(renderer.data().summary(), t);
    let stats = renderer.slice(t, None)?;
    let colours = RenderTarget::new(&gpu, "demo spacetime", w, h, ColorFormat::Rgba8)?;
    let Pixels::Rgba8(c) = renderer.render(&colours, &view)? else { bail!("RGBA8 target returned floats") };
    write_png_rgba8(&out.join("spacetime.png"), w, h, &c)?;
    let values = RenderTarget::new(&gpu, "demo spacetime fields", w, h, ColorFormat::Rgba32F)?;
    let Pixels::Rgba32F(v) = renderer.render(&values, &view)? else { bail!("float target returned bytes") };
    write_exr_rgba(&out.join("spacetime.exr"), w, h, &v)?;
    // Its own check: a flat view from above against the CPU f64 fields at every 4th pixel.
    let flat = galerkin::spacetime::SpacetimeView::from_above(renderer.data().summary(), t);
    let Pixels::Rgba32F(d) = renderer.render(&values, &flat)? else { bail!("float target returned bytes") };
    let hs = renderer.default_height_scale();
    let check = galerkin::spacetime::reference::check_flat_pixels(&mesh, &flat, hs, (w, h), &d, 4, 1e-4);
    if !check.passed() {
        bail!(
            "spacetime: {} of {} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.checked,
            check.first_failure.unwrap_or_default()
        );
    }
    println!(
        "spacetime: {} elements (analytic pulses, L2-projected per element), t = {t:.3}: {} triangles → {}, {} (U, |v|, n_x, n_y); flat view checked at {} pixels against f64: worst U {:.1e}, |v| {:.1e} of max",
        mesh.tets.len(),
        stats.triangles,
        out.join("spacetime.png").display(),
        out.join("spacetime.exr").display(),
        check.checked,
        check.worst_u,
        check.worst_speed
    );
    drop((renderer, colours, values));
    cli::spectral::demo(&gpu, (w, h), out)?;
    cli::radiosity::demo(&gpu, (w, h), out)?;
    cli::fluid::demo(&gpu, (w, h), out)?;
    cli::fluid_reduced::demo(&gpu, (w, h), out)?;
    check_validation(gpu)
}

#[cfg(feature = "viewer")]
fn view(
    desc: GpuDesc,
    scene_path: &Path,
    frames: Option<u64>,
    screenshot: PathBuf,
    resize_to: Option<(u32, u32)>,
) -> Result<()> {
    let scene = DemoScene::load(scene_path)?;
    let options = galerkin::render::viewer::ViewOptions { frames, screenshot, resize_to, keys: Vec::new() };
    galerkin::render::viewer::run(desc, Box::new(galerkin::demo::viewer::DemoContent::new(scene)), options)
}

#[cfg(not(feature = "viewer"))]
fn view(_: GpuDesc, _: &Path, _: Option<u64>, _: PathBuf, _: Option<(u32, u32)>) -> Result<()> {
    bail!("this build has no viewer: rebuild with the default `viewer` feature")
}

/// Parses `WIDTHxHEIGHT`.
pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("{s:?} is not WIDTHxHEIGHT"))?;
    let n = |v: &str| v.trim().parse::<u32>().ok().filter(|&v| (1..=16384).contains(&v));
    match (n(w), n(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("{s:?}: width and height must be 1 to 16384")),
    }
}

fn bench_gpu(desc: &GpuDesc, quick: bool) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    let config =
        if quick { galerkin::bench::BenchConfig::quick() } else { galerkin::bench::BenchConfig::full() };
    let bar = indicatif::ProgressBar::new(5);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut step = 0;
    let rows = galerkin::bench::run(&gpu, &config, |name| {
        bar.set_position(step);
        bar.set_message(name.to_string());
        step += 1;
    })?;
    bar.finish_and_clear();
    let c = gpu.caps();
    println!(
        "device: {} — {} — Vulkan {}.{}.{}",
        c.device_name, c.driver, c.api_version.0, c.api_version.1, c.api_version.2
    );
    println!("cpu peers: {} threads; medians of {} runs\n", galerkin::bench::cpu::threads(), config.reps);
    print!("{}", galerkin::bench::table(&rows));
    check_validation(gpu)
}

fn bench_reduce(desc: &GpuDesc, quick: bool) -> Result<()> {
    let gpu = Gpu::new(desc).ok();
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template("premultiplying V {bar:30} {percent}% eta {eta}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let progress = |done: f64, total: f64| bar.set_position((1000.0 * done / total.max(1.0)) as u64);
    let mut emit = |section: &str| {
        bar.suspend(|| print!("{section}"));
    };
    galerkin::bench::reduce::report(quick, gpu.as_ref(), Some(&progress), &mut emit)?;
    bar.finish_and_clear();
    match gpu {
        Some(g) => check_validation(g),
        None => Ok(()),
    }
}
