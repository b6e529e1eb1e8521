//! `galerkin`: the command-line front end, `galerkin <capability> <verb> [args]`: `spectral`,
//! `spacetime`, `radiosity` and `fluid` with their verbs (`render`, `view`, `gen`, `bench`, …),
//! plus `info`, `demo` and `bench gpu|reduce|all`. It parses and prints; the work is the
//! library's. A capability without a verb prints its help (exit 0); argument errors exit 2.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

mod cli {
    pub mod args;
    pub mod fluid;
    pub mod fluid_reduced;
    pub mod progress;
    pub mod radiosity;
    pub mod ranks;
    pub mod spacetime;
    pub mod spectral;
}
use clap::{Parser, Subcommand};
use galerkin::demo::scene::DemoScene;
use galerkin::gpu::{shaders, Gpu, GpuDesc};
use galerkin::reduce::Communicator;

/// galerkin: reduced simulation by non-polynomial Galerkin projection and pixel-exact
/// rendering of high-order solutions, on Vulkan.
///
/// Environment: GALERKIN_DEVICE=<substring> picks a device by name; GALERKIN_VALIDATION=1
/// turns on the Khronos validation layer; VK_DRIVER_FILES selects Vulkan drivers (e.g.
/// /usr/share/vulkan/icd.d/lvp_icd.json for lavapipe); GALERKIN_LOG=debug shows diagnostics.
#[derive(Parser)]
#[command(version, about, long_about, arg_required_else_help = true)]
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
    /// Run every capability's demo, check each against its CPU reference, and write images to
    /// --out (`make demo`); with --view, open the demo scene in a window instead (Esc quits, S
    /// saves a screenshot PNG, arrow keys orbit the camera).
    Demo(DemoArgs),
    /// Spectral elements drawn per pixel (seed 002): VTK Lagrange/Bézier cells, MFEM and GLVis
    /// files or generated data sets, planar, surfaces in 3D, hexahedra by cut planes.
    #[command(arg_required_else_help = true)]
    Spectral {
        #[command(subcommand)]
        verb: cli::spectral::Verb,
    },
    /// Time slices of spacetime discontinuous-Galerkin data sets (seed 003): .gst and .vtu.
    #[command(arg_required_else_help = true)]
    Spacetime {
        #[command(subcommand)]
        verb: cli::spacetime::Verb,
    },
    /// Radiosity on deforming scenes (seed 000 §8–9): full and reduced, pictures, a viewer,
    /// training, the reduced model's error and speed.
    #[command(arg_required_else_help = true)]
    Radiosity {
        #[command(subcommand)]
        action: cli::radiosity::Action,
    },
    /// Fluids on deforming simplicial meshes (seed 000 §5–7): the full-space solver, reduced
    /// models (training, runs, comparisons), pictures, viewers, ParaView export.
    #[command(arg_required_else_help = true)]
    Fluid {
        #[command(subcommand)]
        action: cli::fluid::Action,
    },
    /// The engine's own benchmarks (the device's ceilings, the reduction core) and `all`,
    /// which runs every capability's benchmark in one go. Each capability's benchmark is its
    /// `bench` verb, e.g. `galerkin spectral bench`.
    #[command(arg_required_else_help = true)]
    Bench {
        #[command(subcommand)]
        what: BenchWhat,
    },
}

/// Arguments of `galerkin demo`.
#[derive(clap::Args)]
#[command(mut_arg("screenshot", |a| a.default_value("out/screenshot.png")))]
struct DemoArgs {
    /// Scene file (TOML; default: the built-in copy of scenes/demo.toml, so the demo runs from
    /// any directory).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    #[command(flatten)]
    viewer: cli::args::ViewerArgs,
    /// With --view and --quit-after: ask for this window size (WIDTHxHEIGHT) halfway through.
    #[arg(long, value_name = "WxH", value_parser = cli::args::parse_size)]
    resize_to: Option<(u32, u32)>,
}

#[derive(Subcommand)]
enum BenchWhat {
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
    /// Every benchmark in one run, one after another, each under its command line as a
    /// heading: gpu, reduce, spectral, spacetime, radiosity, fluid and fluid's reduced step.
    /// The full sizes take about 15 minutes on two cores, plus generating the spacetime data
    /// sets (6 GB, into out/bench-data/) the first time; --quick takes a few minutes. With
    /// --out, the tables are also written into FILE between the lines
    /// `<!-- begin: galerkin bench all -->` and `<!-- end: galerkin bench all -->` (the rest of
    /// FILE is kept; a FILE that does not exist is created), under one line naming the commit,
    /// date, device, driver and CPU: `galerkin bench all --out BENCHMARKS.md` regenerates the
    /// reference tables.
    All {
        /// Each benchmark at its quick sizes.
        #[arg(long)]
        quick: bool,
        /// Write the tables into this Markdown file, between its markers (atomically, after
        /// every benchmark has succeeded).
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
}

fn main() {
    let ranks = match cli::ranks::open() {
        Ok(ranks) => ranks,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(1);
        }
    };
    // Logs from rank 0 only.
    let filter = match ranks.is_root() {
        true => tracing_subscriber::EnvFilter::try_from_env("GALERKIN_LOG")
            .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn,winit=error")),
        false => tracing_subscriber::EnvFilter::new("off"),
    };
    // Escape codes only on a terminal: a log file gets plain text.
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(cli::progress::to_terminal())
        .init();
    // Ctrl-C and SIGTERM remove the unfinished files a command was writing, then exit 130.
    if let Err(e) = galerkin::atomic_file::remove_on_interrupt() {
        tracing::warn!("{e}");
    }
    let matches = match <Cli as clap::CommandFactory>::command().try_get_matches() {
        Ok(matches) => matches,
        // `galerkin spectral` (a capability without its verb): its help, as --help gives it.
        Err(e) if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            print!("{}", e.render());
            std::process::exit(0);
        }
        Err(e) => e.exit(),
    };
    if let Some(message) = cli::args::inapplicable(&matches) {
        <Cli as clap::CommandFactory>::command()
            .error(clap::error::ErrorKind::ArgumentConflict, message)
            .exit();
    }
    let cli = match <Cli as clap::FromArgMatches>::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let desc = desc(&cli);
    let result = run(&desc, cli.command, &*ranks);
    // Validation is checked once, here, after every device of the command is dropped (their
    // leak reports are in the log too).
    // A failed command is checked too: what it left behind must be cleaned up.
    let validation = validation_result(&desc);
    for e in [&result, &validation].into_iter().filter_map(|r| r.as_ref().err()) {
        if ranks.size() > 1 {
            // A failing rank stops all with its message (MPI aborts the job).
            ranks.fail(&format!("{e:#}"));
        }
        eprintln!("error: {e:#}");
    }
    if result.is_err() || validation.is_err() {
        std::process::exit(1);
    }
}

fn desc(cli: &Cli) -> GpuDesc {
    let mut d = GpuDesc::from_env();
    if let Some(name) = &cli.device {
        d.device_name = Some(name.clone());
    }
    d.validation |= cli.validation;
    if d.validation {
        d.validation_log = Some(std::sync::Arc::default());
    }
    d
}

/// Fails if validation was on and reported errors.
fn validation_result(desc: &GpuDesc) -> Result<()> {
    let errors = desc.validation_log.as_ref().map(|log| log.errors()).unwrap_or_default();
    match errors.first() {
        Some(first) => bail!("{} Vulkan validation error(s); the first: {first}", errors.len()),
        None => Ok(()),
    }
}

fn run(desc: &GpuDesc, command: Command, ranks: &dyn Communicator) -> Result<()> {
    let over_ranks = matches!(
        &command,
        Command::Radiosity { action: cli::radiosity::Action::Train(_) }
            | Command::Fluid { action: cli::fluid::Action::Train(_) | cli::fluid::Action::TrainScene(_) }
    );
    if ranks.size() > 1 && !over_ranks {
        bail!(
            "{} ranks: only `radiosity train`, `fluid train` and `fluid train-scene` run over MPI ranks; run other commands without mpirun",
            ranks.size()
        );
    }
    match command {
        Command::Info => info(desc),
        Command::Demo(args) if args.viewer.view => view(desc.clone(), &args),
        Command::Demo(args) => demo(desc, args.scene.as_deref(), &args.out),
        Command::Spacetime { verb } => cli::spacetime::run(desc, &verb),
        Command::Spectral { verb } => cli::spectral::run(desc, &verb),
        Command::Radiosity { action } => cli::radiosity::run(desc, &action, ranks),
        Command::Fluid { action } => cli::fluid::run(desc, &action, ranks),
        Command::Bench { what: BenchWhat::Gpu { quick } } => bench_gpu(desc, quick),
        Command::Bench { what: BenchWhat::Reduce { quick } } => bench_reduce(desc, quick),
        Command::Bench { what: BenchWhat::All { quick, out } } => bench_all(desc, quick, out.as_deref()),
    }
}

/// The command lines `galerkin bench all` runs, quick or full.
fn bench_all_commands(quick: bool) -> Vec<&'static str> {
    if quick {
        vec![
            "bench gpu --quick",
            "bench reduce --quick",
            "spectral bench --quick",
            "spacetime bench --quick",
            "radiosity bench scenes/radiosity/two_rooms_small.toml",
            "fluid bench --quick",
            "fluid bench-reduced --quick",
        ]
    } else {
        vec![
            "bench gpu",
            "bench reduce",
            "spectral bench",
            "spacetime bench",
            "radiosity bench",
            "fluid bench",
            "fluid bench-reduced",
        ]
    }
}

/// Runs each benchmark as its own process (the `galerkin` being run, with this run's
/// `--device` and `--validation`), echoing and capturing its tables; with `out`, writes them
/// into that file between its markers once every benchmark has succeeded.
fn bench_all(desc: &GpuDesc, quick: bool, out: Option<&Path>) -> Result<()> {
    use galerkin::bench::report;
    // The file's markers are checked before the benchmarks, and the file is read again after
    // them, so edits made to it meanwhile are kept.
    let read = |path: &Path| std::fs::read_to_string(path).with_context(|| format!("{}", path.display()));
    if let Some(path) = out.filter(|p| p.exists()) {
        report::splice(&read(path)?, "", path).map_err(anyhow::Error::msg)?;
    }
    let exe = std::env::current_exe().context("cannot find the running galerkin binary")?;
    let mut global = Vec::new();
    if let Some(name) = &desc.device_name {
        global.extend(["--device".to_string(), name.clone()]);
    }
    if desc.validation {
        global.push("--validation".to_string());
    }
    let commands = bench_all_commands(quick);
    let mut runs = Vec::with_capacity(commands.len());
    for (k, line) in commands.iter().enumerate() {
        println!("\n# `galerkin {line}` ({} of {})\n", k + 1, commands.len());
        let args: Vec<String> =
            global.iter().cloned().chain(line.split_whitespace().map(String::from)).collect();
        let run = report::run_captured(&exe, &args, line).map_err(anyhow::Error::msg)?;
        println!("\n(`galerkin {line}`: {:.0} s)", run.seconds);
        runs.push(run);
    }
    let Some(out) = out else { return Ok(()) };
    let caps = Gpu::new(desc)?.caps().clone();
    // The commit is the source tree the binary was built in (target/release/ lies inside it).
    let provenance =
        report::Provenance::read(exe.parent().unwrap_or(Path::new(".")), &caps.device_name, &caps.driver);
    let all = if quick { "bench all --quick" } else { "bench all" };
    let generated = report::generated_section(&provenance, all, &runs);
    let doc = match out.exists() {
        true => report::splice(&read(out)?, &generated, out).map_err(anyhow::Error::msg)?,
        false => report::new_document(&generated),
    };
    galerkin::atomic_file::write(out, doc.as_bytes()).with_context(|| format!("{}", out.display()))?;
    eprintln!(
        "tables written to {} ({})",
        out.display(),
        provenance.line(&format!("galerkin {all}"), runs.iter().map(|r| r.seconds).sum())
    );
    Ok(())
}

pub(crate) use cli::progress::progress_bar;

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
        "features      shaderFloat64 {}, geometryShader {}, fillModeNonSolid {}, dynamicRendering {}",
        c.shader_float64, c.geometry_shader, c.fill_mode_non_solid, c.dynamic_rendering
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
    drop(gpu);
    Ok(())
}

/// The demo scene: the file given, or the built-in copy of scenes/demo.toml.
fn demo_scene(path: Option<&Path>) -> Result<DemoScene> {
    Ok(match path {
        Some(path) => DemoScene::load(path)?,
        None => DemoScene::parse(include_str!("../scenes/demo.toml"), Path::new("scenes/demo.toml"))?,
    })
}

fn demo(desc: &GpuDesc, scene_path: Option<&Path>, out: &Path) -> Result<()> {
    let scene = demo_scene(scene_path)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let gpu = Gpu::new(desc)?;
    let caps = gpu.caps();
    println!("device: {} — {}", caps.device_name, caps.driver);
    galerkin::demo::run::run(&gpu, &scene, out, &mut |part| println!("{part}"))?;
    Ok(())
}

#[cfg(feature = "viewer")]
fn view(desc: GpuDesc, args: &DemoArgs) -> Result<()> {
    let scene = demo_scene(args.scene.as_deref())?;
    let options = galerkin::render::viewer::ViewOptions {
        frames: args.viewer.quit_after,
        screenshot: args.viewer.screenshot.clone(),
        resize_to: args.resize_to,
        keys: Vec::new(),
    };
    galerkin::render::viewer::run(desc, Box::new(galerkin::demo::viewer::DemoContent::new(scene)), options)
}

#[cfg(not(feature = "viewer"))]
fn view(_: GpuDesc, _: &DemoArgs) -> Result<()> {
    bail!("this build has no viewer: rebuild with the default `viewer` feature")
}

fn bench_gpu(desc: &GpuDesc, quick: bool) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    let config =
        if quick { galerkin::bench::BenchConfig::quick() } else { galerkin::bench::BenchConfig::full() };
    let bar = progress_bar(5, "device ceilings");
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
    drop(gpu);
    Ok(())
}

fn bench_reduce(desc: &GpuDesc, quick: bool) -> Result<()> {
    let gpu = Gpu::new(desc).ok();
    let bar = progress_bar(1000, "premultiplying V (per mille)");
    let progress = |done: f64, total: f64| bar.set_position((1000.0 * done / total.max(1.0)) as u64);
    let mut emit = |section: &str| {
        bar.suspend(|| print!("{section}"));
    };
    galerkin::bench::reduce::report(quick, gpu.as_ref(), Some(&progress), &mut emit)?;
    bar.finish_and_clear();
    drop(gpu);
    Ok(())
}
