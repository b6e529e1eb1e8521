//! `galerkin fluid …`: seed 000 §5–7's full-space fluid on deforming simplicial meshes.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use galerkin::fluid::run::simulate_run;
use galerkin::fluid::scene::FluidScene;
use galerkin::fluid::snapshots::SnapshotReader;
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::reduce::Communicator;
use galerkin::render::Colormap;

/// `galerkin fluid` subcommands.
#[derive(Subcommand)]
pub enum Action {
    /// Simulate a scene in the full space (seed 000 Fig. 2, left) and write its snapshots
    /// (u, p, f, g, h per frame; the format is documented in src/fluid/snapshots.rs) to
    /// --out. Prints the per-stage times (t_a advection + diffusion, t_p projection).
    Simulate(SimulateArgs),
    /// Draw one frame of a snapshot directory: in 2D the cells by speed or plain, in 3D the
    /// domain's walls as a cutaway (far walls shaded, near ones culled); marker particles
    /// advected from frame 0 on the device (Eq. 13, 10 Euler substeps per frame) on top; to PNG
    /// (with a title — run, frame, time — and a colour bar of the speed beside the picture,
    /// unless --no-legend) or EXR (EXR: the raw value, cell index and kind — 0 cell, 1
    /// particle, 2 wall — beside the colour).
    #[command(mut_arg("out", |a| a.default_value("out/fluid.png")), mut_arg("size", |a| a.help("Image size, WIDTHxHEIGHT [default: 1280x720; a 2D run is fitted into it]")))]
    Render(RenderArgs),
    /// Play a 2D scene in a window (the full simulation steps every frame, the particles are
    /// advected on the device; keys: space plays/pauses, c colours cells by speed, r
    /// restarts), a 2D reduced model replaying a training run, or a 3D cavity model driven
    /// live (keys 1-3 compress or release a small cavity, space pauses, r resets, p reseeds
    /// the particles, arrows orbit). Esc quits, S saves a screenshot.
    #[command(mut_arg("screenshot", |a| a.default_value("out/fluid-screenshot.png")))]
    View(ViewArgs),
    /// Write the surface animation of a [bird] or [surface] scene as an OBJ sequence
    /// (DIR/{stem}_0000.obj, …: one object per closed part, the same topology every frame),
    /// for other tools or to edit and load back through a [surface] scene.
    Surface(SurfaceArgs),
    /// Train a reduced model (seed 000 §6) on full runs of one mesh: bases B_f, B_u = B_p,
    /// B_g, B_h by PCA of the snapshots and B_d by constraint reduction, then the reduced
    /// tensors of §6.2 premultiplied; writes one safetensors file.
    Train(crate::cli::fluid_reduced::TrainArgs),
    /// Run a reduced model (Fig. 2 right: matrix-exponential advection, constrained reduced
    /// projection) and write its frames lifted to the full space as a snapshot directory, which
    /// `galerkin fluid render` draws.
    Reduced(crate::cli::fluid_reduced::ReducedArgs),
    /// Train a reduced model from a scene in one resumable command: simulate its training runs
    /// (the cavity's 14, or the bird's animation), build the bases, premultiply the tensors.
    /// Run it again to resume: finished runs and bases are kept in the work directory.
    TrainScene(crate::cli::fluid_reduced::TrainSceneArgs),
    /// Compare a model's reduced run with the full run of the same motion (a training run —
    /// the cavity's simulated again, or any scene's read from its training snapshots with
    /// --full — or cavity compressions no run made): energy and velocity error over time,
    /// plots, and the last frame's error on the plane z = 0.
    Compare(crate::cli::fluid_reduced::CompareArgs),
    /// The one-step error study of seed 000 §7.1 (Fig. 5 d, e): train on RUNS at the largest
    /// basis size, then for every size step the test run's projected frames once in the full
    /// and once in the reduced space; writes CSV and labelled PNG plots.
    ErrorStudy(crate::cli::fluid_reduced::StudyArgs),
    /// Write a snapshot directory (a full run, or a reduced run lifted by `fluid reduced`) as
    /// a ParaView time series: RUN.pvd listing RUN/RUN_000000.vtu, … with each frame's time;
    /// per cell velocity, speed, the outward flux through each face and the divergence (the
    /// format in src/fluid/export.rs).
    Export(ExportArgs),
    /// The full-space solver (seed 000 §5, Table 1): seconds per step for deformation,
    /// advection and projection on the deforming cavity from 10³ to 3·10⁵ cells next to the
    /// paper's, and particle advection (10,000 particles) on the CPU and the device.
    Bench(BenchArgs),
    /// The reduced fluid (seed 000 §6): the reduced step at Table 1's cavity basis sizes
    /// (m_f 64, m_u 128, m_g 5, m_h 16) on synthetic bases of the cavity mesh, stage by stage
    /// with the Krylov and Padé exponentials; and 10⁶ reduced steps of a small tunnel model
    /// watching the energy (trained first into out/bench-fluid-reduced/).
    BenchReduced(crate::cli::fluid_reduced::BenchArgs),
}

/// Arguments of `galerkin fluid export`.
#[derive(Args)]
pub struct ExportArgs {
    /// Snapshot directory (written by `fluid simulate`, `fluid reduced` or `fluid train-scene`).
    pub dir: PathBuf,
    /// The collection to write (.pvd); the frames go to a directory of the same name.
    #[arg(long)]
    pub out: PathBuf,
    /// Export every N-th frame (and the last).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
}

/// Arguments of `galerkin fluid surface`.
#[derive(Args)]
pub struct SurfaceArgs {
    /// Scene file (TOML) with a [bird] or [surface] section, e.g. scenes/fluid/bird.toml.
    pub scene: PathBuf,
    /// Directory to write the OBJ files to (created).
    #[arg(long, default_value = "out/bird-obj")]
    pub out: PathBuf,
    /// File name stem.
    #[arg(long, default_value = "frame")]
    pub stem: String,
}

/// Arguments of `galerkin fluid view`.
#[derive(Args)]
pub struct ViewArgs {
    /// Scene file (TOML), 2D, e.g. scenes/fluid/tunnel_small.toml — or a model file
    /// (.safetensors): a 2D model replays a training run, a 3D cavity model is driven by keys.
    #[arg(required_unless_present = "model")]
    pub scene: Option<PathBuf>,
    /// Play a reduced model (written by `galerkin fluid train`) instead of a scene.
    #[arg(long, conflicts_with = "scene")]
    pub model: Option<PathBuf>,
    /// With --model: the motion, replay:K for training run K.
    #[arg(long, default_value = "replay:0")]
    pub motion: galerkin::fluid::reduced::ReducedMotion,
    /// Marker particles.
    #[arg(long, default_value_t = 8000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_PARTICLES))]
    pub particles: usize,
    /// Window size, WIDTHxHEIGHT [default: 1280x720; a 2D run is fitted into it].
    #[arg(long, value_name = "WxH", value_parser = crate::cli::args::parse_size)]
    pub size: Option<(u32, u32)>,
    /// --play starts the simulation or the motion.
    #[command(flatten)]
    pub viewer: crate::cli::args::ViewerArgs,
    /// Keys pressed at frames in a scripted run, KEY@FRAME comma-separated (a cavity model:
    /// 1, 2, 3 compress or release a small cavity, space pauses, r resets, p reseeds).
    #[arg(long, default_value = "")]
    pub keys: galerkin::render::viewer::ScriptedKeys,
}

/// Arguments of `galerkin fluid simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// Scene file (TOML), e.g. scenes/fluid/tunnel_small.toml.
    pub scene: PathBuf,
    /// Frames to simulate (default: the scene's `flow.frames`).
    #[arg(long, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: Option<usize>,
    /// Snapshot directory to write.
    #[arg(long, default_value = "out/fluid")]
    pub out: PathBuf,
    /// Overwrite a directory that already holds snapshots.
    #[arg(long)]
    pub force: bool,
    /// Cavity scenes: the training run (0 to 13) instead of the scene's `run`.
    #[arg(long)]
    pub run: Option<usize>,
    /// Cavity scenes: drive the three small cavities by compressions no training run made
    /// instead — FRAME=A1/A2/A3 keyframes, comma-separated, interpolated linearly and held
    /// after the last (see `fluid reduced --drive`); frames default to the last keyframe's.
    /// The full run `fluid compare --full` compares a driven reduced run with.
    #[arg(long, conflicts_with = "run")]
    pub drive: Option<galerkin::fluid::reduced::CompressionSchedule>,
}

/// Arguments of `galerkin fluid render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Snapshot directory written by `galerkin fluid simulate`.
    pub dir: PathBuf,
    /// Frame to draw (default: the last).
    #[arg(long)]
    pub frame: Option<usize>,
    /// Marker particles, seeded at frame 0 (0: none).
    #[arg(long, default_value_t = 4000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_PARTICLES))]
    pub particles: usize,
    /// Colour the cells by speed (the particles then draw white); otherwise the cells are
    /// grey and the particles carry the speed colours.
    #[arg(long)]
    pub cells: bool,
    /// The speed's colours (range default: 0 to the frame's largest cell speed).
    #[command(flatten)]
    pub colour: crate::cli::args::ColourArgs,
    #[command(flatten)]
    pub image: crate::cli::args::ImageArgs,
    /// A 3D run's camera (--camera, --fit; a 2D run is drawn flat).
    #[command(flatten)]
    pub view_from: crate::cli::args::CameraArgs,
    /// The domain's outline and axis triad (--outline, --axes).
    #[command(flatten)]
    pub overlay: crate::cli::args::OverlayArgs,
    /// A PNG without its title and colour bar (the bare picture).
    #[arg(long)]
    pub no_legend: bool,
    /// Particle sprite radius in pixels.
    #[arg(long, default_value_t = 1.6)]
    pub sprite: f64,
}

/// Runs a `galerkin fluid` action.
pub fn run(desc: &GpuDesc, action: &Action, ranks: &dyn Communicator) -> Result<()> {
    match action {
        Action::Simulate(args) => simulate(args),
        Action::Render(args) => render(desc, args),
        Action::View(args) => view(desc, args),
        Action::Surface(args) => surface(args),
        Action::Export(args) => export(args),
        Action::Train(args) => crate::cli::fluid_reduced::train(args, ranks),
        Action::Reduced(args) => crate::cli::fluid_reduced::reduced(args),
        Action::TrainScene(args) => crate::cli::fluid_reduced::train_scene(args, ranks),
        Action::Compare(args) => crate::cli::fluid_reduced::compare(desc, args),
        Action::ErrorStudy(args) => crate::cli::fluid_reduced::error_study(args),
        Action::Bench(args) => bench(desc, args),
        Action::BenchReduced(args) => crate::cli::fluid_reduced::bench(desc, args),
    }
}

fn export(args: &ExportArgs) -> Result<()> {
    let frames = SnapshotReader::open(&args.dir)?.meta().frames;
    let bar = crate::progress_bar(frames.div_ceil(args.every.max(1)) as u64 + 1, "exporting frames");
    let out = galerkin::fluid::export::export_run(&args.dir, &args.out, args.every, &mut |done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let out = out?;
    println!(
        "{}: {} frames of {} (relative divergence at most {:.1e}), in {}",
        out.pvd.display(),
        out.frames.len(),
        args.dir.display(),
        out.relative_divergence,
        args.out.with_extension("").display()
    );
    Ok(())
}

fn surface(args: &SurfaceArgs) -> Result<()> {
    let scene = FluidScene::load(&args.scene)?;
    let Some(animation) = scene.animation() else {
        bail!("{}: only [bird] and [surface] scenes have a surface animation", args.scene.display());
    };
    let files = animation.write_sequence(&args.out, &args.stem)?;
    println!(
        "fluid surface: {} frames of {} triangles ({} parts) → {}",
        files.len(),
        animation.triangles.len(),
        animation.parts.len(),
        args.out.join(format!("{}_*.obj", args.stem)).display()
    );
    Ok(())
}

#[cfg(feature = "viewer")]
fn view(desc: &GpuDesc, args: &ViewArgs) -> Result<()> {
    use galerkin::fluid::viewer::FluidContent;
    use galerkin::fluid::viewer_cavity::CavityContent;
    use galerkin::render::viewer::{run, ViewOptions, ViewerContent};
    // A model file given in the scene's place is a model.
    let is_model = |p: &std::path::Path| p.extension().is_some_and(|e| e == "safetensors");
    let model = args.model.clone().or_else(|| args.scene.clone().filter(|p| is_model(p)));
    let content: Box<dyn ViewerContent> = match (&args.scene, model) {
        (_, Some(model)) => {
            let model = galerkin::fluid::reduced::ReducedFluidModel::load(&model)?;
            if model.cavity.is_some() {
                Box::new(CavityContent::new(
                    model,
                    args.particles,
                    args.size.unwrap_or(galerkin::picture::DEFAULT_SIZE),
                    args.viewer.play,
                )?)
            } else {
                Box::new(FluidContent::reduced(
                    model,
                    args.motion,
                    args.particles,
                    args.size.unwrap_or(galerkin::picture::DEFAULT_SIZE),
                    args.viewer.play,
                )?)
            }
        }
        (Some(scene), None) => Box::new(FluidContent::new(
            FluidScene::load(scene)?,
            args.particles,
            args.size.unwrap_or(galerkin::picture::DEFAULT_SIZE),
            args.viewer.play,
        )?),
        (None, None) => bail!("give a scene file or a model"),
    };
    let options = ViewOptions {
        frames: args.viewer.quit_after,
        screenshot: args.viewer.screenshot.clone(),
        keys: args.keys.0.clone(),
        ..ViewOptions::default()
    };
    run(desc.clone(), content, options)
}

#[cfg(not(feature = "viewer"))]
fn view(_: &GpuDesc, _: &ViewArgs) -> Result<()> {
    bail!("this build has no window: rebuild with the `viewer` feature (on by default)")
}

fn simulate(args: &SimulateArgs) -> Result<()> {
    let mut scene = FluidScene::load(&args.scene)?;
    if let Some(run) = args.run {
        scene.set_run(run)?;
    }
    let frames = args.frames.unwrap_or(args.drive.as_ref().map_or(scene.frames, |d| d.last_frame()));
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    println!(
        "fluid: {} ({}) — {}D, {} cells, {} faces ({} on the boundary), {} vertices",
        args.scene.display(),
        scene.description,
        mesh.dim(),
        mesh.cell_count(),
        topo.face_count(),
        topo.boundary_faces().len(),
        mesh.vertex_count(),
    );
    let bar = crate::progress_bar(frames as u64, "simulating");
    let mut on_frame =
        |_: usize, solver: &galerkin::fluid::FluidSolver, state: &galerkin::fluid::FluidState, _: &_| {
            bar.set_message(format!("energy {:.4}", solver.energy(state)));
            bar.inc(1);
        };
    let summary = match &args.drive {
        Some(schedule) => galerkin::fluid::run::simulate_driven(
            &mut scene,
            schedule,
            frames,
            &args.out,
            args.force,
            &mut on_frame,
        )?,
        None => simulate_run(&mut scene, frames, &args.out, args.force, &mut on_frame)?,
    };
    bar.finish_and_clear();
    if frames == 0 {
        println!("the initial state only (0 frames simulated) → {}", args.out.display());
        return Ok(());
    }
    let [td, ta, tp] = summary.stage_medians();
    println!(
        "{frames} frames (setup {:.2} s): t_d {:.4} s (deformation), t_a {:.4} s (advection + diffusion, {} RK4 substeps), t_p {:.4} s (projection: {:.1} multigrid-preconditioned CG steps per frame) per frame (medians); energy {:.5} → {:.5}; worst relative divergence {:.1e} → {}",
        summary.setup_seconds,
        td,
        ta,
        summary.substeps,
        tp,
        summary.cg_steps_per_frame(),
        summary.energy.0,
        summary.energy.1,
        summary.worst_divergence,
        args.out.display()
    );
    Ok(())
}

/// `galerkin fluid render` ([`galerkin::fluid::picture::write_frame`]).
fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    use galerkin::fluid::picture::{write_frame, FrameRequest};
    let request = FrameRequest {
        frame: args.frame,
        particles: args.particles,
        colormap: Colormap::by_name(&args.colour.colormap)?,
        range: args.colour.range,
        colour_cells: args.cells,
        sprite_px: args.sprite,
        size: args.image.size,
        orbit: args.view_from.orbit(args.image.size()),
        overlay: args.overlay.overlay(),
        legend: !args.no_legend,
    };
    let gpu = Gpu::new(desc)?;
    let start = Instant::now();
    let bar = crate::progress_bar(0, "advecting particles");
    let r = write_frame(&gpu, &args.dir, &request, &args.image.out, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    });
    bar.finish_and_clear();
    let r = r?;
    println!(
        "fluid render: frame {} of {} ({} cells, {} particles), speed range {:.3}..{:.3}, {:.2} s → {}",
        r.frame,
        args.dir.display(),
        r.cells,
        args.particles,
        r.range.0,
        r.range.1,
        start.elapsed().as_secs_f64(),
        args.image.out.display()
    );
    drop(gpu);
    Ok(())
}

/// Arguments of `galerkin fluid bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Smaller sizes and fewer frames: a minute instead of several.
    #[arg(long)]
    pub quick: bool,
    /// Frames measured per size (medians are reported).
    #[arg(long, default_value_t = 5, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: usize,
}

/// `galerkin fluid bench` ([`galerkin::bench::fluid::report`]).
pub fn bench(desc: &GpuDesc, args: &BenchArgs) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    galerkin::bench::fluid::report(&gpu, args.quick, args.frames, &mut |s| print!("{s}"))
}
