//! `galerkin radiosity …`: seed 000 §8–9's radiosity on the deforming two-room scene.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::near_field::FormFactorMethod;
use galerkin::radiosity::picture::{write_picture, PictureRequest};
use galerkin::radiosity::reduced::ReducedRadiosity;
use galerkin::radiosity::render::{Shading, Viewpoint};
use galerkin::radiosity::train::TrainOptions;
use galerkin::radiosity::train_stages::{train_and_save, WorkOptions};
use galerkin::radiosity::LightMode;
use galerkin::reduce::effectivity::Effectivity;
use galerkin::reduce::Communicator;

/// `galerkin radiosity` subcommands.
#[derive(Subcommand)]
pub enum Action {
    /// Solve the radiosity of a scene at one parameter vector — full (Eq. 14 with the form
    /// factors of Eq. 15, visibility by ray casting) or, with --model, reduced — and draw it
    /// to PNG (tone-mapped sRGB) or EXR (the raw radiance R, G, B and the face index beside
    /// the colour). With --view, open the viewer at this configuration instead.
    #[command(
        mut_arg("out", |a| a.default_value("out/radiosity.png")),
        mut_arg("screenshot", |a| a.default_value("out/radiosity-screenshot.png"))
    )]
    Render(RenderArgs),
    /// Open the scene (the two rooms or an OBJ scene) in a window: keys change the design
    /// parameters (1–9 choose one, [/] lower/raise it; in the two rooms also w/W window, k/K
    /// skylight, d/D door, t/T tilt), f switches reduced/full (with --model), m flat/smooth
    /// shading, e/E exposure, space sweeps the parameters; the title shows the mode, the
    /// parameters, the solve's time and the frame rate.
    #[command(mut_arg("screenshot", |a| a.default_value("out/radiosity-screenshot.png")))]
    View(ViewArgs),
    /// Train the reduced radiosity of a scene (seed 000 §8.2–8.3, §9): sample the design
    /// space, solve every sample in full, PCA every quantity of Table 2, premultiply, learn
    /// the visibility; writes DIR/model.safetensors and DIR/visibility.safetensors.
    Train(TrainArgs),
    /// Run the two animation sequences through the design space (420 and 500 frames, many
    /// configurations not trained on) reduced and full, and report the per-frame relative
    /// error, the frame rates and their ratio: a table (CSV) and a plot (PNG).
    Compare(CompareArgs),
    /// Full radiosity (seed 000 §8): form factors with visibility and the Jacobi solve of
    /// Eq. 14, on the CPU and the device, for the small and the full two-room scene. The
    /// reduced model's rate is measured by `galerkin radiosity compare`.
    Bench(BenchArgs),
}

/// Arguments of `galerkin radiosity train`.
#[derive(Args)]
pub struct TrainArgs {
    /// Scene file (TOML). Area lights only (the sky's direct light is outside the model).
    pub scene: PathBuf,
    /// Output directory.
    #[arg(long, default_value = "out/radiosity-model")]
    pub out: PathBuf,
    /// Number of sampled configurations (the paper: 540): every axis's extremes, the corners
    /// of the parameter box, then a Latin hypercube.
    #[arg(long, default_value_t = 540, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub samples: usize,
    /// Fraction of each quantity's variance its basis keeps (the paper: 0.999).
    #[arg(long, default_value_t = 0.999)]
    pub energy: f64,
    /// Fraction of the radiosity's (and emission's) variance the radiosity basis B_b keeps (the
    /// paper: 0.999 like the others; with the operator correction B_b's own truncation is most
    /// of the error, and 0.9999 is not slower at run time).
    #[arg(long, default_value_t = 0.9999)]
    pub radiosity_energy: f64,
    /// Most vectors per quantity's basis (the paper: 60; the merged e/b basis gets twice).
    #[arg(long, default_value_t = 60)]
    pub cap: usize,
    /// Seed of the Latin hypercube.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Override the scene's lighting: area (emitting openings, inside the model) or sky
    /// (direct light from an overcast sky computed at run time outside it).
    #[arg(long, value_parser = ["area", "sky"])]
    pub lights: Option<String>,
    /// Form factors of near pairs: `exact` (the default with area lights: exact polygon form
    /// factors for visible pairs within 4 face diameters, in the training solves and in the
    /// model as a precomputed correction blended by Eq. 17's weights; about 3× the training
    /// time) or `centroid` (Table 2 as printed: Eq. 15 with the regularised near field, low
    /// where faces meet; the default and the only choice with sky lighting).
    #[arg(long, value_parser = ["centroid", "exact"])]
    pub near_field: Option<String>,
    /// Table 2's chain alone: no correction of the reduced operator at the training
    /// configurations (by default the model stores the chain's error in the reduced operator
    /// at every sample, B_bᵀρF_tB_b − Ê⊗₂p̂_t, and blends it with Eq. 17's weights; it needs
    /// --near-field centroid).
    #[arg(long)]
    pub no_operator_correction: bool,
    /// Greedy training: start from every axis's extremes and the box's corners, then add full
    /// solves where the model's own error estimate is worst over --candidates random
    /// configurations (and the corners), --batch per round, retraining each round, until the
    /// worst estimate is below --tolerance or --budget solves are spent (--samples is not
    /// used). Writes greedy.csv and greedy.png beside the model.
    #[arg(long)]
    pub greedy: bool,
    /// Greedy: stop once the worst estimated error over the candidates is below this fraction.
    #[arg(long, default_value_t = 0.02, value_parser = positive_fraction, requires = "greedy")]
    pub tolerance: f64,
    /// Greedy: most full solves in all.
    #[arg(long, default_value_t = 540, requires = "greedy", value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub budget: usize,
    /// Greedy: random candidate configurations the estimate is evaluated at each round.
    #[arg(long, default_value_t = 2000, requires = "greedy", value_parser = crate::cli::args::count_up_to(galerkin::reduce::effectivity::MAX_RANDOM))]
    pub candidates: usize,
    /// Greedy: full solves added per round (each round retrains).
    #[arg(long, default_value_t = 20, requires = "greedy", value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub batch: usize,
    /// Work directory: each finished stage of the training (samples, solves — each kept as it
    /// finishes —, bases, tensors, correction, model) is kept here, so the same command run
    /// again after a kill or a crash resumes where it stopped. Refused if it holds the work
    /// of another scene or other options. Removed once the model is written unless
    /// --keep-work [default: OUT/work]
    #[arg(long, conflicts_with = "greedy")]
    pub work: Option<PathBuf>,
    /// Keep the work directory once the model is written (its solves take about 4 MB per
    /// sample at 4,876 faces)
    #[arg(long, conflicts_with = "greedy")]
    pub keep_work: bool,
}

/// Arguments of `galerkin radiosity view`.
#[derive(Args, Clone)]
pub struct ViewArgs {
    /// Scene file (TOML); with --model, by default the scene the model was trained on (a
    /// scene given is checked to be that one).
    #[arg(required_unless_present = "model")]
    pub scene: Option<PathBuf>,
    /// A trained model's directory: start in reduced mode (f switches to full).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// The starting configuration and view (arrow keys orbit, m toggles the shading).
    #[command(flatten)]
    pub look: Look,
    /// Window size, WIDTHxHEIGHT.
    #[arg(long, value_name = "WxH", value_parser = crate::cli::args::parse_size, default_value = "1280x720")]
    pub size: (u32, u32),
    /// --play sweeps the parameters (space toggles).
    #[command(flatten)]
    pub viewer: crate::cli::args::ViewerArgs,
}

/// Arguments of `galerkin radiosity compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// Scene file (TOML); by default the one the model records it was trained on (a scene
    /// given is checked to be that one: a changed scene is refused, naming both hashes).
    /// Needed with --full-only.
    pub scene: Option<PathBuf>,
    /// The trained model's directory.
    #[arg(long, default_value = "out/radiosity-model")]
    pub model: PathBuf,
    /// Frames of the two sequences (the paper: 420 and 500).
    #[arg(long, value_delimiter = ',', default_values_t = [420, 500])]
    pub frames: Vec<usize>,
    /// Where the table (compare.csv) and the plot (compare.png) go.
    #[arg(long, default_value = "out/radiosity-compare")]
    pub out: PathBuf,
    /// Override the scene's lighting (must match the model's).
    #[arg(long, value_parser = ["area", "sky"])]
    pub lights: Option<String>,
    /// Keep the full radiosity of every frame in DIR and reuse it on later runs with the same
    /// scene file, lighting and frames (the full solution does not depend on the model): such a
    /// run solves only --timed-full frames per sequence again, for the speed ratio measured in
    /// the same run and to check the kept frames against. A run stopped part way keeps what it
    /// solved (saved every 50 frames); the next goes on from there.
    #[arg(long, value_name = "DIR")]
    pub full_frames: Option<PathBuf>,
    /// With kept full frames: how many full frames per sequence are solved again.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..))]
    pub timed_full: u64,
    /// Eq. 17's form: `local` (ours: the 48 nearest training configurations and a locality
    /// term, so a training configuration gets its own visibility back) or `printed` (every
    /// training configuration, no locality term).
    #[arg(long, value_parser = ["local", "printed"], default_value = "local")]
    pub eq17: String,
    /// Only solve and keep the full frames in --full-frames DIR (resuming), without a model:
    /// they depend on the scene alone, so they can be made before or while a model trains.
    #[arg(long, requires = "full_frames")]
    pub full_only: bool,
    /// The full frames' form factors: `exact` (exact polygon form factors for near pairs: the
    /// accurate full radiosity, about 8× slower per full frame) or `centroid` (Eq. 15 with the
    /// regularised near field). By default what the model was trained with: `exact` for a
    /// model carrying the exact near field, else `centroid` (then the error is the
    /// reduction's alone, not the centroid form factors' bias).
    #[arg(long, value_parser = ["centroid", "exact"])]
    pub full_near_field: Option<String>,
    /// Also solve this many configurations drawn uniformly from the design space, full and
    /// reduced (random.csv): the error and the model's estimate of it away from the sequences.
    #[arg(long, default_value_t = 0, value_parser = crate::cli::args::count_up_to(galerkin::reduce::effectivity::MAX_RANDOM))]
    pub random: usize,
    /// The random configurations' seed (unrelated to training's sampling).
    #[arg(long, default_value_t = 2026)]
    pub random_seed: u64,
    /// The estimated error above which a frame counts as untrusted in the summary.
    #[arg(long, value_name = "FRACTION", default_value_t = galerkin::radiosity::estimate::DEFAULT_THRESHOLD, value_parser = positive_fraction)]
    pub trust_threshold: f64,
}

/// What a picture or window shows: the configuration and how it is looked at.
#[derive(Args, Clone)]
pub struct Look {
    /// Design parameters as NAME=VALUE, comma-separated or repeated: the two rooms' are
    /// window_width, skylight_size, door_width (metres), ceiling_tilt (degrees); an OBJ scene's
    /// are its deformation targets' names. Unset ones take the scene's defaults; values outside
    /// the scene's ranges are refused.
    #[arg(long = "params", value_name = "NAME=VALUE", value_delimiter = ',', value_parser = parse_param)]
    pub params: Vec<(String, f64)>,
    /// Viewpoint in the two rooms (an OBJ scene is seen from outside its bounds).
    #[arg(long, value_enum, default_value_t = Viewpoint::Living)]
    pub viewpoint: Viewpoint,
    /// Flat (each face's radiosity) or smooth (averaged to the vertices) shading.
    #[arg(long, value_enum, default_value_t = Shading::Flat)]
    pub shading: Shading,
    /// Exposure (1 / radiance shown at 63 % of white, positive); default: automatic from the
    /// solution.
    #[arg(long, value_parser = crate::cli::args::positive_number, allow_hyphen_values = true)]
    pub exposure: Option<f64>,
}

/// Arguments of `galerkin radiosity render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML): the two rooms (scenes/radiosity/two_rooms.toml, 4,876 faces;
    /// two_rooms_small.toml, 496) or an OBJ scene — a TOML file naming its base OBJ
    /// (`base = "room.obj"`), its deformation targets (one OBJ per parameter), albedos,
    /// openings (the objects light enters through) and lights; the format is in
    /// docs/radiosity.md. An OBJ file itself is not a scene. With --model, by default the
    /// scene the model was trained on (a scene given is checked to be that one).
    #[arg(required_unless_present = "model")]
    pub scene: Option<PathBuf>,
    /// A trained model's directory (`galerkin radiosity train`): draw the reduced radiosity.
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Override the scene's lighting: area (emitting openings) or sky (overcast sky outside).
    #[arg(long, value_parser = ["area", "sky"])]
    pub lights: Option<String>,
    /// The configuration and the view.
    #[command(flatten)]
    pub look: Look,
    #[command(flatten)]
    pub image: crate::cli::args::ImageArgs,
    /// The camera orbiting the scene's bounding box (--camera, --fit), instead of --viewpoint.
    #[command(flatten)]
    pub view_from: crate::cli::args::CameraArgs,
    /// The scene's outline and axis triad (--outline, --axes).
    #[command(flatten)]
    pub overlay: crate::cli::args::OverlayArgs,
    /// A PNG without its title and colour bar (the bare picture; the bar is the tone map's
    /// radiance scale).
    #[arg(long)]
    pub no_legend: bool,
    /// Also write the per-face result as a table, to check it outside the engine: CSV (face,
    /// part, kind, area, centroid, radiosity R, G, B — f64 that reads back to the same bits)
    /// or NumPy .npy (faces × 8 f64: kind 0 surface / 1 window / 2 skylight, area, centroid,
    /// radiosity R, G, B).
    #[arg(long, value_name = "FILE.csv|FILE.npy", value_parser = table_path)]
    pub faces: Option<PathBuf>,
    /// The full solve's form factors for near pairs: `exact` (the default: exact polygon form
    /// factors for pairs within 4 face diameters — the accurate radiosity, and what `radiosity
    /// train` trains against by default with area lights) or `centroid` (Eq. 15 with the
    /// regularised near field: Table 2 as printed, about 20 % low on the small scene's
    /// receiving surfaces, about 8× faster). A model evaluates its own form factors: not with
    /// --model.
    #[arg(long, value_parser = ["centroid", "exact"], conflicts_with = "model")]
    pub near_field: Option<String>,
    /// With --model: the estimated relative error (receiving surfaces) above which the reduced
    /// radiosity is reported untrusted and not drawn — so is a configuration whose reduced
    /// operator has a non-positive eigenvalue, at any threshold.
    #[arg(long, value_name = "FRACTION", default_value_t = galerkin::radiosity::estimate::DEFAULT_THRESHOLD, value_parser = positive_fraction, requires = "model")]
    pub trust_threshold: f64,
    /// With --model: draw the reduced radiosity even where it is untrusted (the estimate is
    /// printed beside it).
    #[arg(long, requires = "model")]
    pub allow_untrusted: bool,
    /// --view opens the viewer at this configuration; --play sweeps the parameters.
    #[command(flatten)]
    pub viewer: crate::cli::args::ViewerArgs,
}

/// A `.csv` path, checked when the arguments are parsed.
fn table_path(s: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(s);
    galerkin::radiosity::face_table::TableFormat::of(&path).map(|_| path)
}

/// A fraction in (0, 1] (an error threshold).
fn positive_fraction(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|_| format!("{s:?} is not a number"))?;
    if v.is_finite() && v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected a fraction in (0, 1], e.g. 0.05 for 5 %"))
    }
}

fn parse_param(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("{s:?}: expected NAME=VALUE"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("{s:?}: the parameter's name is empty"));
    }
    let v: f64 = value.trim().parse().map_err(|_| format!("{name}: {value:?} is not a number"))?;
    Ok((name.to_string(), v))
}

/// Runs a `galerkin radiosity` subcommand.
pub fn run(desc: &GpuDesc, action: &Action, ranks: &dyn Communicator) -> Result<()> {
    match action {
        Action::Render(args) => render(desc, args),
        Action::Train(args) => train(args, ranks),
        Action::View(args) => view(desc, args),
        Action::Compare(args) => compare(args),
        Action::Bench(args) => bench(desc, args),
    }
}

fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    let size = args.image.size();
    if args.viewer.view {
        let view_args = ViewArgs {
            scene: args.scene.clone(),
            model: args.model.clone(),
            look: args.look.clone(),
            size,
            viewer: args.viewer.clone(),
        };
        return view(desc, &view_args);
    }
    let model = args.model.as_deref().map(ReducedRadiosity::load).transpose()?;
    let scene_path = scene_file(args.scene.as_deref(), model.as_ref())?;
    let scene = AnyScene::load(&scene_path, light_mode(args.lights.as_deref()))?;
    let p = scene.parameters_from(&args.look.params).with_context(|| format!("{}", scene_path.display()))?;
    let request = PictureRequest {
        params: p.clone(),
        viewpoint: args.look.viewpoint,
        orbit: args.view_from.orbit(size),
        overlay: args.overlay.overlay(),
        shading: args.look.shading,
        exposure: args.look.exposure,
        size,
        faces: args.faces.clone(),
        form_factors: match args.near_field.as_deref() {
            Some("centroid") => FormFactorMethod::Centroid,
            _ => FormFactorMethod::ExactNear { reach: galerkin::radiosity::near_field::DEFAULT_REACH },
        },
        trust_threshold: (!args.allow_untrusted).then_some(args.trust_threshold),
        legend: !args.no_legend,
    };
    let gpu = Gpu::new(desc)?;
    let out = &args.image.out;
    let r =
        write_picture(&gpu, &scene, model.as_ref(), &request, out).with_context(|| match &args.model {
            Some(dir) => format!("{} with the model {}", scene_path.display(), dir.display()),
            None => scene_path.display().to_string(),
        })?;
    if let Some(table) = &args.faces {
        println!("per-face table ({} faces, f64) → {}", r.faces, table.display());
    }
    if let Some(e) = &r.estimate {
        match e.error.is_finite() {
            true => println!(
                "estimated error over the receiving surfaces: {:.2} % (reduced operator: σ_min {:.3}, margin {:.3})",
                100.0 * e.error,
                e.stability,
                e.margin
            ),
            false => println!(
                "no error estimate (the model was trained without one: train again); reduced operator: σ_min {:.3}, margin {:.3}",
                e.stability, e.margin
            ),
        }
        if let Some(why) = e.untrusted(args.trust_threshold) {
            eprintln!("warning: drawn with --allow-untrusted, but the reduced radiosity is not to be trusted here: {why}");
        }
    }
    let p_text: Vec<String> = scene.names().iter().zip(&p).map(|(n, v)| format!("{n}={v}")).collect();
    println!(
        "radiosity: {} faces, {} lights, {}; {} {:.3} s, exposure {:.3} → {}",
        r.faces,
        if r.lights == LightMode::Sky { "sky" } else { "area" },
        p_text.join(" "),
        r.how,
        r.solve_seconds,
        r.exposure,
        out.display()
    );
    drop(gpu);
    Ok(())
}

/// The scene file a command uses: the one given, checked against `model`'s provenance, or the
/// one `model` records ([`ReducedRadiosity::scene_file`]).
fn scene_file(given: Option<&std::path::Path>, model: Option<&ReducedRadiosity>) -> Result<PathBuf> {
    match (given, model) {
        (given, Some(m)) => Ok(m.scene_file(given)?),
        (Some(p), None) => Ok(p.to_path_buf()),
        (None, None) => {
            bail!("name a scene file, or a model (--model DIR) that records the scene it was trained on")
        }
    }
}

/// The `--lights` choice as a light mode (`None`: the scene file's own).
fn light_mode(lights: Option<&str>) -> Option<LightMode> {
    lights.map(|l| if l == "sky" { LightMode::Sky } else { LightMode::Area })
}

/// `galerkin radiosity train` ([`galerkin::radiosity::train_stages::train_and_save`]), over MPI
/// ranks when `mpirun` started it: progress and results from rank 0 only.
fn train(args: &TrainArgs, ranks: &dyn Communicator) -> Result<()> {
    let scene = AnyScene::load(&args.scene, light_mode(args.lights.as_deref()))?;
    let options = TrainOptions {
        samples: args.samples,
        energy: args.energy,
        radiosity_energy: Some(args.radiosity_energy),
        cap: args.cap,
        radiosity_cap: 2 * args.cap,
        seed: args.seed,
        operator_correction: !args.no_operator_correction,
        near_correction: match (args.near_field.as_deref(), scene.space().lights().mode) {
            (Some("exact"), _) | (None, galerkin::radiosity::LightMode::Area) => {
                Some(galerkin::radiosity::near_field::DEFAULT_REACH)
            }
            _ => None,
        },
        ..TrainOptions::default()
    };
    if args.greedy {
        return train_greedy(args, &scene, &options, ranks);
    }
    let bars = std::sync::Mutex::new(std::collections::BTreeMap::<String, indicatif::ProgressBar>::new());
    let source = Some((args.scene.as_path(), scene.content_sha256(&args.scene)?));
    let work = WorkOptions { dir: args.work.clone(), keep: args.keep_work, stop_after: None };
    let trained = train_and_save(
        scene.space(),
        &options,
        &args.out,
        source,
        &work,
        &|stage, done, total| {
            if !ranks.is_root() {
                return;
            }
            let mut bars = bars.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let label = match stage {
                "solve" => "full radiosity of samples",
                "gram" => "Gram matrices of the pair quantities (pairs)",
                "pca" => "PCA of Table 2's quantities",
                "orthonormalise" => "orthonormalising the pair bases (pairs)",
                "correct" => "the reduced operator at every sample",
                _ => "premultiplying tensors (chunks of pairs)",
            };
            let bar = bars.entry(stage.to_string()).or_insert_with(|| crate::progress_bar(total, label));
            bar.set_length(total);
            bar.set_position(done);
        },
        // One line per stage, on stderr (also when it is a log file, not a terminal).
        &mut |stage| {
            if ranks.is_root() {
                let mut bars = bars.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                for bar in std::mem::take(&mut *bars).into_values() {
                    bar.finish();
                }
                eprintln!("radiosity train: {}", stage.line());
            }
        },
        ranks,
    );
    for bar in bars.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner).values() {
        bar.finish();
    }
    let t = trained?;
    if !ranks.is_root() {
        return Ok(());
    }
    println!(
        "radiosity train: {} faces, {} samples solved in {:.1} s, trained in {:.1} s → {}",
        t.model.faces(),
        t.configurations,
        t.solve_seconds,
        t.train_seconds,
        args.out.display()
    );
    println!("| quantity | full dimension | vectors | variance kept |\n|---|---:|---:|---:|");
    for (name, dim, m, energy) in &t.report.bases {
        println!("| {name} | {dim} | {m} | {:.4} % |", 100.0 * energy);
    }
    for (name, m) in &t.report.merged {
        println!("merged basis {name}: {m} vectors");
    }
    if let Some(c) = &t.report.correction {
        println!(
            "the reduced operator is corrected at every sample (Q: blended by Eq. 17's weights); before the correction, Table 2's chain was {:.3} % (mean) and {:.3} % (worst, sample {}) off the exact operator projected on B_b",
            100.0 * c.mean_discrepancy,
            100.0 * c.worst_discrepancy,
            c.worst_configuration
        );
    }
    if t.model.trained_near_field() == galerkin::radiosity::reduced::TrainedNearField::Exact {
        println!("the training solves used the exact near field (the correction carries it into the model)");
    }
    println!("model size on disk: {:.1} MB", t.bytes_on_disk as f64 / 1e6);
    Ok(())
}

/// `galerkin radiosity train --greedy` ([`galerkin::radiosity::greedy::greedy_train`]).
fn train_greedy(
    args: &TrainArgs,
    scene: &AnyScene,
    options: &TrainOptions,
    ranks: &dyn Communicator,
) -> Result<()> {
    use galerkin::radiosity::greedy::greedy_train;
    use galerkin::reduce::greedy::{write_rounds, GreedyOptions};
    if ranks.size() > 1 {
        bail!(
            "--greedy runs on one rank (its rounds retrain on the samples so far); start it without mpirun"
        );
    }
    let greedy = GreedyOptions {
        tolerance: args.tolerance,
        budget: args.budget,
        candidates: args.candidates,
        batch: args.batch,
        seed: args.seed.wrapping_add(1),
    };
    let bar = crate::progress_bar(args.budget as u64, "greedy training: full solves");
    let start = std::time::Instant::now();
    let result = greedy_train(scene.space(), options, &greedy, &|stage, done, _| {
        if stage == "greedy" {
            bar.set_position(done);
        }
    });
    bar.finish();
    let g = result.with_context(|| format!("greedy training of {}", args.scene.display()))?;
    let params: Vec<Vec<f64>> = g.configurations.iter().map(|c| c.params.clone()).collect();
    let provenance = scene.provenance(&args.scene, format!("{options:?} {greedy:?}"), &params)?;
    let model = g.model.with_provenance(provenance);
    model.save(&args.out)?;
    let (csv, plot) = write_rounds(&args.out, &scene.names(), &g.rounds).map_err(anyhow::Error::msg)?;
    println!("| round | full solves | worst estimate | median estimate | unstable candidates | seconds |\n|---:|---:|---:|---:|---:|---:|");
    for (k, r) in g.rounds.iter().enumerate() {
        println!(
            "| {} | {} | {:.2} % | {:.2} % | {} | {:.1} |",
            k + 1,
            r.solves,
            100.0 * r.worst_estimate,
            100.0 * r.median_estimate,
            r.unstable,
            r.seconds
        );
    }
    let last = g.rounds.last().map_or(f64::NAN, |r| r.worst_estimate);
    println!(
        "radiosity train --greedy: {} faces, {} full solves, worst estimated error {:.2} % ({} the tolerance {:.2} %), {:.1} s → {} ({} and {})",
        model.faces(),
        g.configurations.len(),
        100.0 * last,
        if last < args.tolerance { "below" } else { "not below: the budget ran out before" },
        100.0 * args.tolerance,
        start.elapsed().as_secs_f64(),
        args.out.display(),
        csv.display(),
        plot.display()
    );
    Ok(())
}

fn compare(args: &CompareArgs) -> Result<()> {
    use galerkin::radiosity::compare::{self, CompareOptions, Progress};
    compare::check_frames(&args.frames)?;
    let exact = FormFactorMethod::ExactNear { reach: galerkin::radiosity::near_field::DEFAULT_REACH };
    // The full frames' form factors: as asked, else as the model was trained (without a
    // model, --full-only: as a model of this lighting trains by default).
    let method_for = |trained_exact: bool| match args.full_near_field.as_deref() {
        Some("exact") => exact,
        Some(_) => FormFactorMethod::Centroid,
        None if trained_exact => exact,
        None => FormFactorMethod::Centroid,
    };
    // The model (not with --full-only, which needs none) names its scene and checks one given.
    let model = (!args.full_only).then(|| ReducedRadiosity::load(&args.model)).transpose()?;
    let scene_path = scene_file(args.scene.as_deref(), model.as_ref())?;
    let scene = AnyScene::load(&scene_path, light_mode(args.lights.as_deref()))?;
    let mut bar: Option<indicatif::ProgressBar> = None;
    let mut progress = |p: Progress| match p {
        Progress::Sequence(_, frames, label) => bar = Some(crate::progress_bar(frames as u64, label)),
        Progress::Frame => {
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
        Progress::SequenceDone(which, report, groups) => {
            if let Some(b) = bar.take() {
                b.finish();
            }
            let (mean, worst) = report.group(0);
            let (all_mean, all_worst) = report.all_faces();
            eprintln!(
                "sequence {}: {} frames; {}: mean {:.2} %, worst {:.2} % (all faces: {:.2} %, {:.2} %)",
                which + 1,
                report.errors.len(),
                groups.names[0],
                100.0 * mean,
                100.0 * worst,
                100.0 * all_mean,
                100.0 * all_worst
            );
        }
    };
    if args.full_only {
        let dir = args.full_frames.as_ref().context("--full-only needs --full-frames DIR")?;
        let method = method_for(scene.space().lights().mode == galerkin::radiosity::LightMode::Area);
        for path in compare::keep_full_frames(&scene, &scene_path, &args.frames, dir, method, &mut progress)?
        {
            eprintln!("full frames kept in {}", path.display());
        }
        return Ok(());
    }
    let mut model = model.context("a model is loaded unless --full-only")?;
    if args.eq17 == "printed" {
        model.set_eq17(galerkin::radiosity::visibility::Eq17::Printed);
    }
    let options = CompareOptions {
        full_form_factors: method_for(
            model.trained_near_field() == galerkin::radiosity::reduced::TrainedNearField::Exact,
        ),
        frames: args.frames.clone(),
        full_frames: args.full_frames.clone(),
        timed_full: args.timed_full as usize,
        out: args.out.clone(),
        random: args.random,
        random_seed: args.random_seed,
    };
    let r = compare::compare(&scene, &scene_path, &model, &options, &mut progress)
        .with_context(|| format!("comparing {} with {}", args.model.display(), scene_path.display()))?;
    let pct = |(m, w): (f64, f64)| format!("{:.2} % | {:.2} %", 100.0 * m, 100.0 * w);
    println!(
        "Relative error against the full solve with {} form factors, area-weighted over faces and channels (emitters: the window and skylight faces); the model {}",
        match options.full_form_factors {
            FormFactorMethod::Centroid => "centroid (regularised near field)",
            FormFactorMethod::ExactNear { .. } => "exact near-field",
        },
        match (model.trained_near_field(), model.has_operator_correction()) {
            (galerkin::radiosity::reduced::TrainedNearField::Exact, _) =>
                "was trained with the exact near field (its operator corrected at every sample)",
            (_, true) => "was trained with centroid form factors (its operator corrected at every sample)",
            (_, false) => "is Table 2's chain alone, with centroid form factors",
        }
    );
    println!(
        "| sequence | frames | receiving surfaces: mean | worst frame | all faces, emitters included: mean | worst frame |\n|---|---:|---:|---:|---:|---:|"
    );
    for (which, s) in r.sequences.iter().enumerate() {
        println!("| {} | {} | {} | {} |", which + 1, s.errors.len(), pct(s.group(0)), pct(s.all_faces()));
    }
    println!(
        "| all | {} | {} | {} |",
        r.sequences.iter().map(|s| s.errors.len()).sum::<usize>(),
        pct(r.overall(Some(0))),
        pct(r.overall(None))
    );
    let (fit_mean, fit_worst) = r.overall_best_fit();
    println!(
        "the radiosity basis's own floor (the full radiosity projected on B_b, receiving surfaces): mean {:.2} %, worst {:.2} %",
        100.0 * fit_mean,
        100.0 * fit_worst
    );
    for (k, name) in r.groups.names.iter().enumerate().skip(1) {
        println!(
            "receiving surfaces of the {name} ({} faces): mean {}",
            r.groups.faces[k].len(),
            pct(r.overall(Some(k))).replace(" | ", ", worst ")
        );
    }
    if let (Some((mean, worst, at)), Some((all_mean, all_worst, _))) =
        (r.corners_overall(Some(0)), r.corners_overall(None))
    {
        let at: Vec<String> = scene.names().iter().zip(at).map(|(n, v)| format!("{n}={v}")).collect();
        println!(
            "corners of the design space ({}, training configurations): receiving surfaces mean {:.2} %, worst {:.2} % (at {}); all faces {:.2} %, {:.2} %",
            r.corners.len(),
            100.0 * mean,
            100.0 * worst,
            at.join(","),
            100.0 * all_mean,
            100.0 * all_worst
        );
    }
    if !r.random.is_empty() {
        let (mean, worst) = compare::mean_worst(r.random.iter().map(|(_, e)| e.groups[0]));
        println!(
            "random configurations ({}, seed {}): receiving surfaces mean {:.2} %, worst {:.2} % → random.csv",
            r.random.len(),
            args.random_seed,
            100.0 * mean,
            100.0 * worst
        );
    }
    let all_frames = || r.sequences.iter().flat_map(|s| &s.errors);
    // (estimate, true error) over the receiving surfaces.
    let pair = |e: &compare::FrameError| (e.estimate.error, e.groups[0]);
    for (what, effectivity) in [
        ("frames", Effectivity::of(all_frames().map(pair))),
        ("corners", Effectivity::of(r.corners.iter().map(|(_, e)| pair(e)))),
        ("random configurations", Effectivity::of(r.random.iter().map(|(_, e)| pair(e)))),
    ] {
        match effectivity {
            Some(e) => println!("error estimate, {what}: {e}"),
            None if model.cross_validation().is_none() => {
                println!("error estimate, {what}: none (the model was trained without it: train again)");
                break;
            }
            None => {}
        }
    }
    let every = all_frames()
        .map(|e| (None, e))
        .chain(r.corners.iter().map(|(p, e)| (Some(p), e)))
        .chain(r.random.iter().map(|(p, e)| (Some(p), e)));
    let (mut untrusted, mut least_margin) = (0, (f64::INFINITY, None));
    for (p, e) in every {
        untrusted += usize::from(e.estimate.untrusted(args.trust_threshold).is_some());
        if e.estimate.margin < least_margin.0 {
            least_margin = (e.estimate.margin, p);
        }
    }
    let checked = all_frames().count() + r.corners.len() + r.random.len();
    println!(
        "untrusted at a threshold of {:.1} % (estimate above it, or a non-positive margin): {untrusted} of {checked}; least margin of the reduced operator {:.3}{}",
        100.0 * args.trust_threshold,
        least_margin.0,
        least_margin.1.map_or(String::new(), |p| {
            let at: Vec<String> = scene.names().iter().zip(p).map(|(n, v)| format!("{n}={v}")).collect();
            format!(" (at {})", at.join(","))
        })
    );
    let (full, reduced) = (r.full_median_s, r.reduced_median_s);
    println!(
        "median frame: full {:.1} ms ({:.2} FPS, {} frames solved in this run), reduced {:.3} ms ({:.0} FPS, mesh build and lift included): {:.0}× faster",
        full * 1e3,
        1.0 / full,
        r.full_solved,
        reduced * 1e3,
        1.0 / reduced,
        full / reduced
    );
    let total: f64 = r.stage_seconds.iter().sum();
    let share = |k: usize| 100.0 * r.stage_seconds[k] / total;
    println!(
        "reduced frame: project g {:.0} %, learned visibility (Eq. 17, and the sky's direct light in sky mode) {:.0} %, Table 2 chain and solve {:.0} %, error estimate {:.0} %, lift b {:.0} % (of the model's own time)",
        share(0),
        share(1),
        share(2),
        share(3),
        share(4)
    );
    println!("→ {}, {} and corners.csv", r.csv.display(), r.plot.display());
    Ok(())
}

/// Arguments of `galerkin radiosity bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Scene files to measure.
    #[arg(default_values = ["scenes/radiosity/two_rooms_small.toml", "scenes/radiosity/two_rooms.toml"])]
    pub scenes: Vec<PathBuf>,
    /// Runs per measurement (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Skip the device (lavapipe takes about a minute per full-scene form-factor pass).
    #[arg(long)]
    pub cpu_only: bool,
}

/// `galerkin radiosity bench`: the full radiosity's stages on the CPU (f64) and the device
/// (f32), medians of `--runs`.
pub fn bench(desc: &GpuDesc, args: &BenchArgs) -> Result<()> {
    let gpu = if args.cpu_only { None } else { Some(Gpu::new(desc)?) };
    if let Some(g) = &gpu {
        println!("device: {}\n", g.caps().device_name);
    }
    let rows = galerkin::bench::radiosity::run(&args.scenes, args.runs, gpu.as_ref())?;
    print!("{}", galerkin::bench::radiosity::table(&rows));
    let reach = galerkin::radiosity::near_field::DEFAULT_REACH;
    let near = galerkin::bench::radiosity::near_field(&args.scenes, reach)?;
    println!("\nThe near field: the full radiosity with centroid form factors (regularised, the default) against exact polygon form factors for near pairs, CPU f64, one run:\n");
    print!("{}", galerkin::bench::radiosity::near_field_table(&near, reach));
    Ok(())
}

#[cfg(feature = "viewer")]
fn view(desc: &GpuDesc, args: &ViewArgs) -> Result<()> {
    use galerkin::radiosity::picture::{automatic_exposure, check_model_faces};
    use galerkin::radiosity::viewer::{RadiosityContent, ViewSettings};
    use galerkin::render::viewer::{run, ViewOptions};
    let model = args.model.as_deref().map(ReducedRadiosity::load).transpose()?;
    let scene_path = scene_file(args.scene.as_deref(), model.as_ref())?;
    // A model fixes the lighting it was trained with.
    let scene = AnyScene::load(&scene_path, model.as_ref().map(ReducedRadiosity::light_mode))?;
    let p = scene.parameters_from(&args.look.params).with_context(|| format!("{}", scene_path.display()))?;
    let mesh = scene.space().mesh(&p)?;
    if let (Some(m), Some(dir)) = (&model, &args.model) {
        check_model_faces(m, mesh.len()).with_context(|| dir.display().to_string())?;
    }
    let exposure = match args.look.exposure {
        Some(e) => e,
        None => automatic_exposure(&scene, &p)?,
    };
    let settings = ViewSettings {
        params: p,
        view: args.look.viewpoint,
        shading: args.look.shading,
        exposure,
        size: args.size,
        playing: args.viewer.play,
    };
    let content = RadiosityContent::new(scene, model, settings)?;
    let options = ViewOptions {
        frames: args.viewer.quit_after,
        screenshot: args.viewer.screenshot.clone(),
        ..ViewOptions::default()
    };
    run(desc.clone(), Box::new(content), options)
}

#[cfg(not(feature = "viewer"))]
fn view(_: &GpuDesc, _: &ViewArgs) -> Result<()> {
    bail!("this build has no window: rebuild with the `viewer` feature (on by default)")
}
