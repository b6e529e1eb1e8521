//! `galerkin radiosity …`: seed 000 §8–9's radiosity on the deforming two-room scene.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::radiosity::render::{
    camera_for, default_exposure, display_radiance, draw_picture, scene_vertices, Shading, Viewpoint,
};
use galerkin::radiosity::{full_radiosity, LightMode, SceneSpec, PARAMETERS};
use galerkin::render::{write_exr_channels, write_png_rgba8};

/// `galerkin radiosity` subcommands.
#[derive(Subcommand)]
pub enum Action {
    /// Solve the full radiosity (Eq. 14 with the form factors of Eq. 15, visibility by ray
    /// casting) of a scene at one parameter vector and draw it to PNG or EXR (EXR: the raw
    /// radiance R, G, B and the face index beside the tone-mapped colour).
    Render(RenderArgs),
}

/// Arguments of `galerkin radiosity render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Scene file (TOML), e.g. scenes/radiosity/two_rooms.toml (about 5,000 faces) or
    /// two_rooms_small.toml (496 faces).
    pub scene: PathBuf,
    /// Design parameters as NAME=VALUE, comma-separated or repeated: window_width,
    /// skylight_size, door_width (metres), ceiling_tilt (degrees). Unset ones take the scene's
    /// defaults; values outside the scene's ranges are refused.
    #[arg(long = "params", value_name = "NAME=VALUE", value_delimiter = ',', value_parser = parse_param)]
    pub params: Vec<(String, f64)>,
    /// Override the scene's lighting: area (emitting openings) or sky (overcast sky outside).
    #[arg(long, value_parser = ["area", "sky"])]
    pub lights: Option<String>,
    /// Viewpoint.
    #[arg(long, value_enum, default_value_t = Viewpoint::Living)]
    pub view: Viewpoint,
    /// Flat (each face's radiosity) or smooth (averaged to the vertices) shading.
    #[arg(long, value_enum, default_value_t = Shading::Flat)]
    pub shading: Shading,
    /// Exposure (1 / radiance shown at 63 % of white); default: automatic from the solution.
    #[arg(long)]
    pub exposure: Option<f64>,
    /// Image size.
    #[arg(long, value_name = "WxH", value_parser = crate::parse_size, default_value = "1024x768")]
    pub size: (u32, u32),
    /// Output image: .png (tone-mapped sRGB) or .exr (colour and raw radiance and face index).
    #[arg(long, default_value = "out/radiosity.png")]
    pub out: PathBuf,
}

fn parse_param(s: &str) -> Result<(String, f64), String> {
    let (name, value) = s.split_once('=').ok_or_else(|| format!("{s:?}: expected NAME=VALUE"))?;
    let name = name.trim();
    if !PARAMETERS.contains(&name) {
        return Err(format!("unknown parameter {name:?} (the scene has {})", PARAMETERS.join(", ")));
    }
    let v: f64 = value.trim().parse().map_err(|_| format!("{name}: {value:?} is not a number"))?;
    Ok((name.to_string(), v))
}

/// Runs a `galerkin radiosity` subcommand.
pub fn run(desc: &GpuDesc, action: &Action) -> Result<()> {
    match action {
        Action::Render(args) => render(desc, args),
    }
}

fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    let ext = args.out.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    if ext != "png" && ext != "exr" {
        bail!("{}: unknown image format {ext:?}: expected .png or .exr", args.out.display());
    }
    let mut spec = SceneSpec::load(&args.scene)?;
    if let Some(mode) = &args.lights {
        spec.lights.mode = if mode == "sky" { LightMode::Sky } else { LightMode::Area };
    }
    let p = spec.parameters_from(&args.params).with_context(|| format!("{}", args.scene.display()))?;
    let start = Instant::now();
    let s = full_radiosity(&spec, &p)?;
    let solve_s = start.elapsed().as_secs_f64();
    let radiance = display_radiance(&s.mesh, &s.geometry, &spec.lights, &s.radiosity);
    let exposure = args.exposure.unwrap_or_else(|| default_exposure(&s.mesh, &s.geometry, &radiance));
    if !(exposure.is_finite() && exposure > 0.0) {
        bail!("--exposure must be positive, got {exposure}");
    }
    let gpu = Gpu::new(desc)?;
    let vertices = scene_vertices(&s.mesh, &s.geometry, &radiance, args.shading);
    let camera = camera_for(&spec, args.view);
    let picture = draw_picture(&gpu, &vertices, &camera, exposure, args.size)?;
    let (w, h) = args.size;
    if ext == "png" {
        write_png_rgba8(&args.out, w, h, &picture.rgba)?;
    } else {
        let byte =
            |c: usize| picture.rgba.chunks_exact(4).map(|p| f32::from(p[c]) / 255.0).collect::<Vec<f32>>();
        let float = |c: usize| picture.raw.chunks_exact(4).map(|p| p[c]).collect::<Vec<f32>>();
        write_exr_channels(
            &args.out,
            w,
            h,
            vec![
                ("R", byte(0)),
                ("G", byte(1)),
                ("B", byte(2)),
                ("radiance.R", float(0)),
                ("radiance.G", float(1)),
                ("radiance.B", float(2)),
                ("face", float(3)),
            ],
        )?;
    }
    let p_text: Vec<String> = PARAMETERS.iter().zip(&p).map(|(n, v)| format!("{n}={v}")).collect();
    println!(
        "radiosity: {} faces, {} lights, {}; full solve {solve_s:.2} s ({} Jacobi sweeps), exposure {exposure:.3} → {}",
        s.mesh.len(),
        if spec.lights.mode == LightMode::Sky { "sky" } else { "area" },
        p_text.join(" "),
        s.sweeps,
        args.out.display()
    );
    drop(picture);
    crate::check_validation(gpu)
}
