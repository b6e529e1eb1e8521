//! The capabilities' parts of `galerkin demo` (see [`super::run`]): spectral elements per
//! pixel (seed 002), full radiosity of the small two-room scene (seed 000 §8), the full-space
//! tunnel with particles and its reduced model (seed 000 §5–7). Each checks its result
//! against a CPU f64 reference and fails naming what differed.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use super::run::DemoPart;
use crate::fluid::render::{cell_speeds, draw_picture, DrawStyle, Projection, View2d};
use crate::gpu::Gpu;
use crate::render::{write_png_rgba8, ColorFormat, Colormap, Pixels, RenderTarget};

/// Spectral elements: 12 curved elements of order 8 per pixel — every covered pixel checked
/// against the f64 reference within its own f32 bound — next to the seed's per-vertex
/// baseline (how far it is off); then the seed's artery, lit with exact normals.
pub fn spectral(gpu: &Gpu, (w, h): (u32, u32), out: &Path) -> Result<Vec<DemoPart>> {
    use crate::spectral::{generate, NodeSet, SpectralRenderer, SpectralView};
    let mesh = Arc::new(generate::annulus(2, 6, 4, 8, NodeSet::GaussLobatto)?);
    let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &Colormap::viridis())?;
    let data = RenderTarget::new(gpu, "demo spectral values", w, h, ColorFormat::Rgba32F)?;
    let per_pixel = SpectralView { overdraw: false, ..SpectralView::default() };
    let per_vertex = SpectralView { per_vertex: true, ..per_pixel.clone() };
    let Pixels::Rgba32F(pp) = renderer.render(&data, &per_pixel)? else {
        bail!("a float target returned bytes")
    };
    let Pixels::Rgba32F(pv) = renderer.render(&data, &per_vertex)? else {
        bail!("a float target returned bytes")
    };
    let view = crate::spectral::View2d::fit(&mesh, w, h);
    let report = crate::spectral::reference::check_pixels(&mesh, 0, 0, &view, (w, h), &pp);
    if !report.passed() {
        bail!("spectral: pixels differ from the f64 reference: {report:?}");
    }
    // The seed's point: what interpolating colours between the nodes loses.
    let (lo, hi) = renderer.range(&per_pixel);
    let (mut n, mut sum, mut worst) = (0usize, 0.0f64, 0.0f64);
    for (a, b) in pp.chunks_exact(4).zip(pv.chunks_exact(4)) {
        if a[3] >= 0.0 && b[3] >= 0.0 {
            let d = f64::from((a[0] - b[0]).abs());
            n += 1;
            sum += d * d;
            worst = worst.max(d);
        }
    }
    let rms = (sum / n.max(1) as f64).sqrt();
    let colour = RenderTarget::new(gpu, "demo spectral", w, h, ColorFormat::Rgba8)?;
    let mut files = Vec::new();
    for (name, view) in [("spectral.png", &per_pixel), ("spectral-per-vertex.png", &per_vertex)] {
        let view = SpectralView { isolines: 12, edges: true, ..view.clone() };
        let Pixels::Rgba8(c) = renderer.render(&colour, &view)? else {
            bail!("an RGBA8 target returned floats")
        };
        let path = out.join(name);
        write_png_rgba8(&path, w, h, &c)?;
        files.push(path);
    }
    let annulus = DemoPart {
        name: "spectral",
        summary: format!(
            "{} curved elements of order 8 per pixel, {} pixels checked against f64 (worst {:.3} of each pixel's f32 bound); per vertex differs by {:.2} % RMS, {:.1} % at worst of the range",
            mesh.elements(),
            report.covered,
            report.max_error_ratio,
            100.0 * rms / (hi - lo),
            100.0 * worst / (hi - lo)
        ),
        files,
    };
    drop(renderer);
    let artery = Arc::new(generate::artery(44, 16, 3, 5, NodeSet::GaussLobatto)?);
    let mut renderer = SpectralRenderer::new(gpu, artery.clone(), &Colormap::viridis())?;
    let view = SpectralView { isolines: 10, ..SpectralView::default() };
    let Pixels::Rgba8(c) = renderer.render(&colour, &view)? else { bail!("an RGBA8 target returned floats") };
    let path = out.join("spectral-artery.png");
    write_png_rgba8(&path, w, h, &c)?;
    let artery = DemoPart {
        name: "spectral",
        summary: format!(
            "the artery ({} curved surface elements, order {}), lit with the exact normals",
            artery.elements(),
            artery.basis.order
        ),
        files: vec![path],
    };
    Ok(vec![annulus, artery])
}

/// Radiosity: the small two-room scene's full radiosity solved on the CPU (f64) and on the
/// device (f32), the device's checked against an f64 solve of its own form factors (1e-5 of the
/// largest value: the Jacobi tolerance is 1e-6), drawn
/// from the living room, every pixel whose neighbourhood sees one face checked against an
/// f64 ray cast (its face, and its radiance to 1e-6 of the largest: f32 storage).
pub fn radiosity(gpu: &Gpu, size: (u32, u32), out: &Path) -> Result<DemoPart> {
    use crate::radiosity::form_factor::{bvh_of, NearField};
    use crate::radiosity::gpu::GpuRadiosity;
    use crate::radiosity::render::{
        camera_for, default_exposure, display_radiance, draw_picture, scene_vertices, Shading, Viewpoint,
    };
    use crate::radiosity::{full_radiosity, SceneSpec};
    // Built in, so the demo runs from any directory.
    let spec = SceneSpec::parse(
        include_str!("../../scenes/radiosity/two_rooms_small.toml"),
        Path::new("scenes/radiosity/two_rooms_small.toml"),
    )?;
    let p = spec.defaults();
    let start = Instant::now();
    let s = full_radiosity(&spec, &p)?;
    let cpu_s = start.elapsed().as_secs_f64();
    let device = GpuRadiosity::new(gpu)?;
    let start = Instant::now();
    let f = device.form_factors(gpu, &s.mesh, NearField::Regularised)?;
    let (b, _) = device.solve(gpu, &f, &s.mesh.albedo, &s.emission, 1e-6, 2000)?;
    let gpu_s = start.elapsed().as_secs_f64();
    let top = s.radiosity.iter().flatten().fold(0.0f64, |m, v| m.max(*v));
    // The device's solve against an f64 direct solve of its own form factors (f32 sums and the
    // 10⁻⁶ stopping rule: 10⁻⁵ of the largest value). Against the CPU's whole solve the two
    // differ also where a grazing pair's visibility flips between f32 and f64 (up to ~10⁻³:
    // tests/radiosity_gpu.rs).
    let same_factors = crate::radiosity::solve::solve_direct(&f.download(gpu)?, &s.mesh.albedo, &s.emission)?;
    let worst = b
        .iter()
        .zip(&same_factors)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
        .fold(0.0f64, f64::max)
        / top;
    if worst > 1e-5 {
        bail!(
            "radiosity: the device's solution differs from an f64 solve of its form factors by {worst:.2e} of the largest value"
        );
    }
    let radiance = display_radiance(&s.mesh, &s.geometry, &spec.lights, &s.radiosity);
    let exposure = default_exposure(&s.mesh, &s.geometry, &radiance);
    let camera = camera_for(&spec, Viewpoint::Living);
    let vertices = scene_vertices(&s.mesh, &s.geometry, &radiance, Shading::Flat);
    let picture = draw_picture(gpu, &vertices, &camera, exposure, size)?;
    let (w, h) = size;
    let bvh = bvh_of(&s.mesh);
    let (mut checked, mut wrong) = (0, 0);
    for py in (0..h).step_by(3) {
        for px in (0..w).step_by(3) {
            let hit = |dx: f64, dy: f64| {
                let (o, d) = camera.ray_through(f64::from(px) + 0.5 + dx, f64::from(py) + 0.5 + dy, w, h);
                bvh.closest_front_hit(o, d).map(|h| h.0)
            };
            let Some(face) = hit(0.0, 0.0) else { continue };
            if [(-0.75, -0.75), (0.75, -0.75), (-0.75, 0.75), (0.75, 0.75)]
                .iter()
                .all(|&(x, y)| hit(x, y) == Some(face))
            {
                checked += 1;
                let k = ((py * w + px) * 4) as usize;
                let r = radiance[face as usize];
                let ok = picture.raw[k + 3] == face as f32
                    && (0..3).all(|c| (f64::from(picture.raw[k + c]) - r[c]).abs() <= 1e-6 * top);
                wrong += usize::from(!ok);
            }
        }
    }
    if wrong > 0 || checked == 0 {
        bail!("radiosity: {wrong} of {checked} checked pixels do not show their face's radiance");
    }
    let path = out.join("radiosity.png");
    write_png_rgba8(&path, w, h, &picture.rgba)?;
    Ok(DemoPart {
        name: "radiosity",
        summary: format!(
            "the two-room scene ({} faces, area lights), full radiosity on the CPU (f64) in {cpu_s:.2} s and on the device (f32) in {gpu_s:.2} s, agreeing to {worst:.1e} of the largest value; {checked} pixels checked against f64 ray casting",
            s.mesh.len()
        ),
        files: vec![path],
    })
}

/// The 2D tunnel at geometry `g` coloured by cell speed (cells, or the device's particles
/// over grey cells), fitted to `size`, written as a PNG to `path`.
fn draw_tunnel(
    gpu: &Gpu,
    (mesh, topo): (&crate::mesh::SimplexMesh, &crate::mesh::Topology),
    (g, f): (&[f64], &[f64]),
    particles: Option<&crate::fluid::gpu::GpuParticles>,
    size: (u32, u32),
    path: &Path,
) -> Result<()> {
    let speeds = cell_speeds(mesh, topo, g, f);
    let top = speeds.iter().fold(0.0f64, |m, v| m.max(*v)).max(1e-12);
    let style = DrawStyle {
        colormap: Colormap::by_name("viridis")?,
        range: (0.0, top),
        log: false,
        colour_cells: particles.is_none(),
        sprite_px: 1.5,
    };
    let (lo, hi) = mesh.bounds();
    let view = View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], size, 0.02);
    let picture =
        draw_picture(gpu, (mesh, topo), g, &speeds, particles, &style, &Projection::Plane(view), size)?;
    write_png_rgba8(path, size.0, size.1, &picture.rgba)?;
    Ok(())
}

/// Fluids: the small tunnel (seed 000 §7.1) simulated for 20 frames (divergence ≤ 1e-10),
/// 3,000 particles advected on the device and on the CPU (95 % within 1e-4: a particle that
/// straddles a face in one of the frames takes the neighbour's velocity for a substep and
/// drifts apart chaotically afterwards), the last frame drawn.
pub fn fluid(gpu: &Gpu, (w, h): (u32, u32), out: &Path) -> Result<DemoPart> {
    use crate::fluid::gpu::GpuParticles;
    use crate::fluid::particles::{advect_particles, seed_particles};
    use crate::fluid::scene::FluidScene;
    use crate::fluid::FluidSolver;
    // Built in, so the demo runs from any directory.
    let scene = FluidScene::parse(
        include_str!("../../scenes/fluid/tunnel_small.toml"),
        Path::new("scenes/fluid/tunnel_small.toml"),
    )?;
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), scene.params)?;
    let mut state = solver.initial_state(mesh.g().to_vec(), &scene.initial_velocity)?;
    let seeds = seed_particles(mesh, 3000);
    let mut device = GpuParticles::new(gpu, mesh, topo, &seeds)?;
    let mut cpu = seeds.clone();
    let dt = scene.params.frame_time;
    let (mut worst_div, mut worst_particle) = (0.0f64, 0.0f64);
    let t = Instant::now();
    for frame in 1..=20 {
        let (next, report) = solver.step(&state, mesh.g(), frame)?;
        worst_div = worst_div.max(report.projection.relative_divergence);
        advect_particles(mesh, topo, &state.g, &next.g, &next.f, dt, 10, &mut cpu);
        device.advect(gpu, mesh, &state.g, &next.g, &next.f, dt, 10)?;
        state = next;
    }
    let seconds = t.elapsed().as_secs_f64();
    let on_device = device.download(gpu)?;
    let period = scene.base.bounds().1[0] - scene.base.bounds().0[0];
    let mut close = 0;
    for (a, b) in cpu.iter().zip(&on_device) {
        let dx = (a.position[0] - b.position[0]).abs();
        let e = dx.min((dx - period).abs()).max((a.position[1] - b.position[1]).abs());
        worst_particle = worst_particle.max(e);
        close += usize::from(e < 1e-4);
    }
    if close * 100 < cpu.len() * 95 || worst_div > 1e-10 {
        bail!(
            "fluid: {close} of {} device particles within 1e-4 of the CPU; divergence {worst_div:.1e}",
            cpu.len()
        );
    }
    let path = out.join("fluid.png");
    draw_tunnel(gpu, (mesh, topo), (&state.g, &state.f), Some(&device), (w, h), &path)?;
    Ok(DemoPart {
        name: "fluid",
        summary: format!(
            "tunnel of {} triangles, 20 frames in {seconds:.2} s (divergence ≤ {worst_div:.0e}); {close} of {} device particles within 1e-4 of the CPU (worst {worst_particle:.1e})",
            mesh.cell_count(),
            cpu.len()
        ),
        files: vec![path],
    })
}

/// Reduced fluids: two small full runs of the tunnel (obstacle scales 0.6 and 1.4) trained
/// into a model, training run 0 replayed in the reduced space and compared with its full run
/// (the lifted velocity within 50 % relative at the last frame: the demo's bases are tiny),
/// the last reduced frame lifted and drawn by speed.
pub fn fluid_reduced(gpu: &Gpu, (w, h): (u32, u32), out: &Path) -> Result<DemoPart> {
    use crate::fluid::reduced::example::small_tunnel_runs;
    use crate::fluid::reduced::{
        run_reduced, BasisSizes, ReducedFluid, ReducedFluidModel, ReducedMotion, TrainingSet,
    };
    let frames = 60;
    let (runs, summaries) = small_tunnel_runs(&out.join("demo-fluid-reduced"), frames)?;
    let mut full_seconds: Vec<f64> =
        summaries.iter().flat_map(|s| s.stage_seconds.iter().map(|t| t[0] + t[1] + t[2])).collect();
    let set = TrainingSet::open(&runs)?;
    let model = ReducedFluidModel::fit(&set, &BasisSizes::default(), &mut |_| {})?;
    let fluid = ReducedFluid::new(&model)?;
    let run = run_reduced(&model, &fluid, ReducedMotion::Replay(0), frames, &mut |_| {})?;
    let bu = model.basis("u").context("the model has no velocity basis")?;
    let truth = set.runs()[0].frame("u", frames)?;
    let last = &run.states[frames];
    let lifted = bu.lift(&last.u);
    let err = (lifted.iter().zip(&truth).map(|(a, b)| (a - b).powi(2)).sum::<f64>()
        / truth.iter().map(|b| b * b).sum::<f64>())
    .sqrt();
    if err.is_nan() || err >= 0.5 {
        bail!("fluid reduced: the replayed run's velocity is {err:.2e} (relative) from the full run's at frame {frames}");
    }
    let mut reduced_seconds: Vec<f64> = run.reports.iter().map(|r| r.total_seconds()).collect();
    let (rs, fs) =
        (crate::bench::median_f64(&mut reduced_seconds), crate::bench::median_f64(&mut full_seconds));
    let (mesh, topo) = model.mesh_and_topology()?;
    let g = model.basis("g").context("the model has no geometry basis")?.lift(&last.g);
    let f = model.basis("f").context("the model has no flux basis")?.lift(&last.f);
    let path = out.join("fluid-reduced.png");
    draw_tunnel(gpu, (&mesh, &topo), (&g, &f), None, (w, h), &path)?;
    Ok(DemoPart {
        name: "fluid reduced",
        summary: format!(
            "tunnel of {} triangles in m_u {}, m_f {}, m_g {} dimensions; {frames} replayed frames at {:.3} ms a step against {:.1} ms full ({:.0}×), velocity {err:.1e} from the full run at frame {frames}",
            mesh.cell_count(),
            model.dim_of("u"),
            model.dim_of("f"),
            model.dim_of("g"),
            1e3 * rs,
            1e3 * fs,
            fs / rs
        ),
        files: vec![path],
    })
}
