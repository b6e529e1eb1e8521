//! `galerkin spectral render|view|gen|bench`: render spectral elements per pixel (seed 002)
//! from a file or a generated data set; write generated data sets to `.vtu`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use galerkin::gpu::{Gpu, GpuDesc};
use galerkin::render::Colormap;
use galerkin::spectral::{generate, NodeSet, SpectralMesh, SpectralView};

/// Where a data set comes from, shared by `spectral render` and `spectral gen`.
#[derive(Args, Clone)]
pub struct Source {
    /// Without FILE: the generated data set: `grid` (8 × 4 straight, skewed quadrilaterals;
    /// fields `waves` and the discontinuous `cells`), `annulus` (4 × 12 curved quadrilaterals,
    /// same fields), `artery` (the seed's 704-element tube with a stenosis) or `coil` (the
    /// seed's 3332-element helix), both surfaces in 3D with field `pressure`, or `shell` (3 × 6
    /// × 4 curved hexahedra with field `temperature`, shown by --cut planes). Analytic fields
    /// with several time steps, sampled at the nodes — not solved.
    #[arg(long, default_value = "annulus", value_parser = clap::builder::PossibleValuesParser::new(generate::DATA_SETS))]
    pub generate: String,
    /// Without FILE: the fields' polynomial order (1 to 12).
    #[arg(long, default_value_t = 4, value_parser = crate::cli::args::polynomial_order)]
    pub order: usize,
    /// Without FILE: the geometry's order for the curved data sets (1 to 12).
    #[arg(long, default_value_t = 3, value_parser = crate::cli::args::polynomial_order)]
    pub geometry_order: usize,
    /// Without FILE: the fields' node set: gll, equispaced, gauss, or bernstein (coefficients).
    #[arg(long, default_value = "gll", value_parser = clap::builder::PossibleValuesParser::new(NodeSet::ALL.map(NodeSet::name)))]
    pub nodes: String,
}

impl Source {
    fn mesh(&self, file: Option<&Path>, grid_functions: &[PathBuf]) -> Result<SpectralMesh> {
        if let Some(path) = file {
            return Ok(galerkin::spectral::load(path, grid_functions)?);
        }
        let set = NodeSet::by_name(&self.nodes).with_context(|| {
            format!("unknown node set {:?} (gll, equispaced, gauss, bernstein)", self.nodes)
        })?;
        Ok(generate::by_name(&self.generate, self.geometry_order, self.order, set)?)
    }
}

/// `galerkin spectral VERB`.
#[derive(clap::Subcommand)]
pub enum Verb {
    /// Render a data set per pixel to PNG (colour, with a title and a colour legend beside the
    /// picture) or EXR (R, G, B of the picture and the raw value, xi, eta and element of every
    /// pixel as float channels — for cut planes value, plane, zeta and element; NaN where no
    /// element, element −(e + 1) where only edge overdraw drew; data only, no legend). With
    /// --view, open the viewer instead.
    #[command(
        mut_arg("out", |a| a.default_value("out/spectral.png"))
    )]
    Render(RenderArgs),
    /// Open the interactive viewer: space plays/pauses the time steps, `.`/`,` step, l log
    /// scale, p colour map, i/I more/fewer iso-lines, e edges, v per-vertex colour, h height
    /// field (planar meshes), r narrows the range to its middle half, R restores it; cut
    /// planes: n adds, c selects, j/k move, o/O turn about z, u/U tilt, x deletes;
    /// isosurfaces: j/k move the selected value, c selects, n adds, x deletes, t transparent;
    /// volumes: k/j more/less opaque; arrows orbit (surfaces, cut planes, isosurfaces,
    /// volumes), +/- zoom, S screenshot, Esc quits.
    #[command(
        mut_arg("out", |a| a.default_value("out/spectral.png").hide(true)),
        mut_arg("size", |a| a.help("Window size, WIDTHxHEIGHT [default: 1280x720]"))
    )]
    View(RenderArgs),
    /// Generate a spectral-element data set to a .vtu file (analytic fields, not solved).
    Gen(GenArgs),
    /// Seed 002's table: FPS of orders 1–8 on the artery (704) and coil (3332) at 1024×768,
    /// per pixel against per vertex in the same run; frame time against pixels and elements.
    Bench(BenchArgs),
}

/// Runs a `galerkin spectral` verb.
pub fn run(desc: &GpuDesc, verb: &Verb) -> Result<()> {
    match verb {
        Verb::Render(args) => render(desc, args),
        Verb::View(args) => {
            let mut args = args.clone();
            args.viewer.view = true;
            render(desc, &args)
        }
        Verb::Gen(args) => generate_file(args),
        Verb::Bench(args) => bench(desc, args),
    }
}

/// Arguments of `galerkin spectral render` and `view`.
#[derive(Args, Clone)]
pub struct RenderArgs {
    /// Data set: a VTK `.vtu` file of Lagrange or Bézier quadrilaterals (planar or a surface in
    /// 3D) or hexahedra (shown by cut planes), or of Lagrange or Bézier triangles (planar or a
    /// surface in 3D, orders 1–10) or tetrahedra (cut planes, orders 1–10), in any encoding VTK
    /// writes; a
    /// `.pvtu` of such pieces (a partitioned data set, read as one); a ParaView `.pvd`
    /// collection or `.vtu.series` of such files (its files are the time steps); an MFEM mesh
    /// ("MFEM mesh v1.0" of quadrilaterals, hexahedra, triangles or tetrahedra, straight or
    /// with a curved `nodes` section) with --gf; or a GLVis
    /// "solution" stream saved to a file. Without it, a data set is generated (--generate).
    pub file: Option<PathBuf>,
    /// With an MFEM mesh (or after a solution stream): a GridFunction file (H1 or L2
    /// collection); repeat for the time steps of one field, named after the first file.
    #[arg(long = "gf", value_name = "FILE")]
    pub grid_functions: Vec<PathBuf>,
    #[command(flatten)]
    pub source: Source,
    /// Surfaces, height fields and cut planes: the camera (--camera, --fit).
    #[command(flatten)]
    pub view_from: crate::cli::args::CameraArgs,
    /// The outline and axis triad (--outline, --axes).
    #[command(flatten)]
    pub overlay: crate::cli::args::OverlayArgs,
    /// The field to show (default: the first): a one-component array of the file's point data,
    /// or of its cell data (drawn constant on each element; `NAME (cells)` where a point array
    /// has the same name). An unknown name lists the fields there are.
    #[arg(long)]
    pub field: Option<String>,
    /// Its time step (0 = first).
    #[arg(long, default_value_t = 0)]
    pub step: usize,
    /// Show a derived field, evaluated per pixel from the elements' exact polynomials, e.g.
    /// 'length(grad(u))', 'log(abs(u) + 1e-6)', 'u - pressure', 'grad(u).x * x'. Names: u (the
    /// --field shown), the file's other fields by name (or field("a name")), x y z (the point),
    /// t (the step's time); grad(f) is a field's physical gradient (a vector: .x .y .z, length,
    /// dot); + - * /, abs sqrt log exp sin cos pow min max clamp. Quadrilateral meshes, per
    /// pixel; needs the `runtime-shaderc` build feature (the shader is compiled at run time).
    #[arg(long, value_name = "EXPR")]
    pub expr: Option<String>,
    #[command(flatten)]
    pub colour: crate::cli::args::ColourArgs,
    /// Logarithmic colour scale (needs a positive range).
    #[arg(long)]
    pub log: bool,
    /// Iso-lines: this many levels across the colour range, one pixel wide.
    #[arg(long, default_value_t = 0)]
    pub isolines: u32,
    /// Draw the element edges (on the true curved edges); with --iso, the curves where each
    /// isosurface meets the element faces.
    #[arg(long)]
    pub edges: bool,
    /// Do not overdraw edges behind the faces (they fill cracks between discontinuous elements).
    #[arg(long)]
    pub no_overdraw: bool,
    /// Colour at the nodes, interpolated (the seed's baseline) instead of per pixel.
    #[arg(long)]
    pub per_vertex: bool,
    /// Planar meshes: show the field as a height field z = SCALE · f, lit with its exact
    /// normals (`--height` alone: the field's range becomes a quarter of the mesh's width).
    #[arg(long, value_name = "SCALE", num_args = 0..=1, default_missing_value = "0", allow_negative_numbers = true, value_parser = finite)]
    pub height: Option<f64>,
    /// Hexahedral meshes: a cut plane, `x=V`, `y=V`, `z=V` or `A,B,C,D` (the plane
    /// A x + B y + C z = D); repeat for several (at most 8). Default: z through the middle.
    #[arg(long = "cut", value_name = "PLANE", value_parser = galerkin::spectral::render::parse_plane)]
    pub cuts: Vec<[f64; 4]>,
    /// Hexahedral and tetrahedral meshes: draw the isosurfaces f = C1, C2, … (comma-separated,
    /// at most 8) per pixel instead of cut planes, each coloured by its value and lit with the
    /// field's exact normal.
    #[arg(long, value_name = "C1,C2,…", value_delimiter = ',', allow_negative_numbers = true, value_parser = finite)]
    pub iso: Vec<f64>,
    /// With --iso: colour the isosurfaces by this field's value on them (a point-data array of
    /// the file, at the same step) instead of by their iso values.
    #[arg(long, value_name = "FIELD", requires = "iso")]
    pub colour_by: Option<String>,
    /// With --iso: the isosurfaces' opacity A in (0, 1]. Below 1 they are transparent — every
    /// crossing of every value along each pixel's ray is composited front to back, each
    /// letting 1 − A of the light behind it through (drawn by the volume pass; no --edges or
    /// --colour-by). With --volume the isosurfaces are such sheets inside the volume, opaque
    /// unless this is given.
    #[arg(long, value_name = "A", requires = "iso", default_value_t = 1.0, value_parser = opacity)]
    pub iso_opacity: f64,
    /// Hexahedral and tetrahedral meshes: volume rendering instead of cut planes — emission
    /// and absorption integrated along every pixel's ray through the curved elements, coloured
    /// by the colour map, opaque by the transfer function (--opacity or --transfer; default:
    /// clear at the bottom of the range, opacity 0.5 at the top).
    #[arg(long)]
    pub volume: bool,
    /// With --volume: the opacity ramp, VALUE:OPACITY points with increasing values (opacity
    /// in [0, 1], linear between points, constant beyond), e.g. `0:0,0.5:0.8,1:0.2`.
    #[arg(long, value_name = "V:A,…", requires = "volume", allow_hyphen_values = true)]
    pub opacity: Option<String>,
    /// With --volume: the transfer function from a file — a ParaView colour-map preset
    /// (.json, "Save preset": its opacity `Points` and, if present, its `RGBPoints` as the
    /// colours) or text lines `value opacity`.
    #[arg(long, value_name = "FILE", requires = "volume", conflicts_with = "opacity")]
    pub transfer: Option<PathBuf>,
    /// With --volume: the opacity unit distance (ParaView's): a slab this thick of opacity A
    /// lets 1 − A of the light through (default: a tenth of the mesh's diagonal).
    #[arg(long, value_name = "D", requires = "volume", value_parser = finite)]
    pub unit_distance: Option<f64>,
    /// Surfaces: the tessellation's screen-space error budget in pixels.
    #[arg(long, default_value_t = 0.5)]
    pub max_error: f64,
    #[command(flatten)]
    pub image: crate::cli::args::ImageArgs,
    /// A PNG of the picture alone (--size exactly), without the title and colour legend.
    #[arg(long)]
    pub no_legend: bool,
    #[command(flatten)]
    pub viewer: crate::cli::args::ViewerArgs,
}

/// An opacity in (0, 1] ([`galerkin::spectral::transfer::Sheets::check_opacity`]).
fn opacity(s: &str) -> Result<f64, String> {
    let a = finite(s)?;
    galerkin::spectral::transfer::Sheets::check_opacity(a).map(|()| a)
}

/// A finite number.
fn finite(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{s:?} is not a finite number")),
    }
}

#[cfg(feature = "viewer")]
fn open_viewer(desc: &GpuDesc, mesh: Arc<SpectralMesh>, view: SpectralView, args: &RenderArgs) -> Result<()> {
    use galerkin::render::viewer::{run, ViewOptions};
    let content = galerkin::spectral::viewer::SpectralContent::new(
        mesh,
        view,
        &args.colour.colormap,
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
fn open_viewer(_: &GpuDesc, _: Arc<SpectralMesh>, _: SpectralView, _: &RenderArgs) -> Result<()> {
    bail!("this build has no viewer: rebuild with the default `viewer` feature")
}

/// Arguments of `galerkin spectral gen`.
#[derive(Args)]
pub struct GenArgs {
    #[command(flatten)]
    pub source: Source,
    /// Output `.vtu` (VTK Lagrange cells, equispaced, every time step as `NAME_t<k>`).
    #[arg(long, value_parser = crate::cli::args::vtu_path)]
    pub out: PathBuf,
}

/// `galerkin spectral gen`.
pub fn generate_file(args: &GenArgs) -> Result<()> {
    let mesh = args.source.mesh(None, &[])?;
    galerkin::spectral::vtu::write(&args.out, &mesh)?;
    println!(
        "{}: {} elements of order {} (analytic fields sampled at the nodes — not solved)",
        args.out.display(),
        mesh.elements(),
        mesh.basis.order
    );
    Ok(())
}

/// `galerkin spectral render` ([`galerkin::spectral::picture::write_picture`]).
pub fn render(desc: &GpuDesc, args: &RenderArgs) -> Result<()> {
    use galerkin::spectral::picture::{check_view, kind, view_warnings, write_picture};
    let loaded = Instant::now();
    let mesh = Arc::new(args.source.mesh(args.file.as_deref(), &args.grid_functions)?);
    let load_ms = loaded.elapsed().as_secs_f64() * 1e3;
    let field = mesh.field_index(args.field.as_deref())?;
    let expression = match &args.expr {
        Some(text) => Some(Arc::new(galerkin::expression::spectral::DerivedField::new(&mesh, text)?)),
        None => None,
    };
    let mut preset_colours = None;
    let volume = if args.volume {
        let range = args.colour.range.unwrap_or_else(|| {
            mesh.value_range(field, args.step.min(mesh.fields[field].steps.len().saturating_sub(1)))
        });
        let (tf, colours) = galerkin::spectral::transfer::transfer_for_view(
            args.opacity.as_deref(),
            args.transfer.as_deref(),
            args.unit_distance,
            range,
            mesh.diagonal(),
        )
        .map_err(|e| anyhow::anyhow!("--volume: {e}"))?;
        preset_colours = colours;
        Some(tf)
    } else {
        None
    };
    let colour_by = match &args.colour_by {
        Some(name) => Some(mesh.field_index(Some(name)).context("--colour-by")?),
        None => None,
    };
    let view = SpectralView {
        colour_by,
        volume,
        field,
        step: args.step,
        range: args.colour.range,
        log: args.log,
        isolines: args.isolines,
        edges: args.edges,
        overdraw: !args.no_overdraw,
        per_vertex: args.per_vertex,
        max_error_px: args.max_error,
        cuts: args.cuts.clone(),
        iso: args.iso.clone(),
        iso_opacity: args.iso_opacity,
        height: args.height,
        expression,
        camera: args.view_from.orbit(args.image.size()).map(|orbit| {
            let (lo, hi) = mesh.bounds();
            orbit.camera(lo, hi)
        }),
        ..SpectralView::default()
    };
    check_view(&mesh, &view)?;
    for w in view_warnings(&mesh, &view) {
        eprintln!("warning: {w}");
    }
    if args.viewer.view {
        if preset_colours.is_some() {
            eprintln!(
                "warning: the viewer shows its own palettes (p cycles them), not the preset's RGBPoints"
            );
        }
        return open_viewer(desc, mesh, view, args);
    }
    let gpu = Gpu::new(desc)?;
    let colormap = match preset_colours {
        Some(c) => c,
        None => Colormap::by_name(&args.colour.colormap)?,
    };
    let name = match &args.expr {
        Some(text) => format!("{text} (u = {})", mesh.fields[field].name),
        None => mesh.fields[field].name.clone(),
    };
    let source = args
        .file
        .as_ref()
        .map_or_else(|| format!("generated {}", args.source.generate), |f| f.display().to_string());
    let time = mesh.fields[field].times.get(args.step).copied().unwrap_or(0.0);
    let title = format!("{source}: {name}, step {} (t = {time})", args.step);
    let out = &args.image.out;
    let size = args.image.size();
    let r = write_picture(
        &gpu,
        mesh.clone(),
        &view,
        &colormap,
        size,
        out,
        galerkin::picture::Decor {
            title: (!args.no_legend).then_some(title.as_str()),
            overlay: args.overlay.overlay(),
        },
    )?;
    let (lo, hi) = r.range;
    println!(
        "spectral: {} {} elements of order {} ({} geometry of order {}), showing {name:?} step {}, range [{lo:.4}, {hi:.4}]; {} triangles ({}), {} edge lines; load {load_ms:.1} ms, render {:.1} ms → {}",
        mesh.elements(),
        kind(&mesh),
        mesh.basis.order,
        mesh.basis.set.name(),
        mesh.geometry.order,
        args.step,
        r.triangles,
        r.triangle_kind,
        r.lines,
        r.render_ms,
        out.display()
    );
    drop(gpu);
    Ok(())
}

/// Arguments of `galerkin spectral bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Orders 1, 3 and 8 only, fewer frames.
    #[arg(long)]
    pub quick: bool,
    /// Frames per measurement (the median is reported).
    #[arg(long, default_value_t = 15, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: usize,
    /// Instead: what derived fields (--expr) cost — shader compile time, device frame time
    /// against the field itself, and the CPU interpreter on the same pixels (needs the
    /// `runtime-shaderc` build feature).
    #[arg(long)]
    pub derived: bool,
    /// Instead: what isosurfaces (--iso) cost against a cut plane of the same mesh and image
    /// (device time, interleaved), and their accuracy against the f64 ray caster. Meshes:
    /// the generated shell at orders 3 and 6, or the files given with --mesh.
    #[arg(long, conflicts_with = "derived")]
    pub iso: bool,
    /// Instead: what volume rendering (--volume) costs against a cut plane of the same mesh
    /// and image (device time, interleaved), and its accuracy against the f64 ray caster.
    /// Mesh: the generated shell at order 3, or the files given with --mesh.
    #[arg(long, conflicts_with_all = ["derived", "iso"])]
    pub volume: bool,
    /// With --iso: transparent isosurfaces (opacity ½, drawn by the volume pass) instead of
    /// opaque ones, at the volume table's sizes, against the f64 ray caster with sheets. Mesh:
    /// the generated shell at order 3, or the files given with --mesh.
    #[arg(long, requires = "iso")]
    pub transparent: bool,
    /// With --iso or --volume: a hexahedral or tetrahedral mesh file to measure (repeatable).
    #[arg(long, value_name = "FILE")]
    pub mesh: Vec<std::path::PathBuf>,
}

/// `galerkin spectral bench`: seed 002's table on this device
/// ([`galerkin::bench::spectral::report`]).
pub fn bench(desc: &GpuDesc, args: &BenchArgs) -> Result<()> {
    let gpu = Gpu::new(desc)?;
    if args.derived {
        return galerkin::bench::spectral_derived::report(&gpu, args.frames, &mut |s| print!("{s}"));
    }
    if args.volume || args.transparent {
        let mut meshes = Vec::new();
        if args.mesh.is_empty() {
            meshes.push(galerkin::bench::spectral_volume::default_mesh()?);
        }
        for f in &args.mesh {
            let mesh = galerkin::spectral::load(f, &[]).with_context(|| f.display().to_string())?;
            meshes.push((f.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned()), mesh));
        }
        let report = if args.transparent {
            galerkin::bench::spectral_volume::report_transparent
        } else {
            galerkin::bench::spectral_volume::report
        };
        return report(&gpu, meshes, args.frames, &mut |s| print!("{s}"));
    }
    if !args.mesh.is_empty() && !args.iso {
        anyhow::bail!("--mesh goes with --iso or --volume");
    }
    if args.iso {
        let meshes = if args.mesh.is_empty() {
            galerkin::bench::spectral_iso::default_meshes()?
        } else {
            args.mesh
                .iter()
                .map(|p| Ok((p.display().to_string(), galerkin::spectral::load(p, &[])?)))
                .collect::<Result<Vec<_>>>()?
        };
        return galerkin::bench::spectral_iso::report(&gpu, meshes, args.frames, &mut |s| print!("{s}"));
    }
    galerkin::bench::spectral::report(&gpu, args.quick, args.frames, &mut |s| print!("{s}"))
}
