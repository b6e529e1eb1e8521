//! A device lost mid-work reaches the caller as a typed device error from every capability, so
//! a host embedding galerkin can tell device loss from a bad input (`GpuFailure`): spectral,
//! spacetime, fluid (device particles and the cell picture), radiosity and the reduction
//! core's premultiplication each run on a `Gpu` whose first submission wait reports the device
//! lost (fault injection), and the error each returns says `is_device_lost()` — not a string
//! that merely mentions it. Allocation failures likewise say `is_out_of_memory()`.

mod common;

use std::sync::Arc;

use galerkin::gpu::{Gpu, GpuError, GpuFailure};
use galerkin::render::{ColorFormat, Colormap, RenderTarget};

/// The fault a test Gpu injects.
#[derive(Clone, Copy, Debug)]
enum Fault {
    /// The first submission wait reports the device lost.
    DeviceLost,
    /// The first allocation fails as out of memory.
    OutOfMemory,
}

/// Runs `work` on a Gpu that injects `fault` and checks that the capability fails, and fails
/// typed: its error answers `is_device_lost()` or `is_out_of_memory()` as the fault says.
fn fails_typed<E: GpuFailure + std::fmt::Display>(
    what: &str,
    fault: Fault,
    work: impl FnOnce(&Gpu) -> Result<(), E>,
) {
    let gpu = common::gpu_with(|d| match fault {
        Fault::DeviceLost => d.lose_device = Some(1),
        Fault::OutOfMemory => d.fail_allocation = Some(1),
    });
    let e = match work(&gpu) {
        Ok(()) => panic!("{what}: succeeded despite {fault:?}"),
        Err(e) => e,
    };
    let (lost, oom) = (e.is_device_lost(), e.is_out_of_memory());
    let typed = match fault {
        Fault::DeviceLost => lost && !oom,
        Fault::OutOfMemory => oom,
    };
    assert!(typed, "{what}: {e} is not {fault:?} to a host ({:?})", e.gpu_error());
}

fn spectral(gpu: &Gpu) -> Result<(), galerkin::spectral::SpectralError> {
    use galerkin::spectral::{generate, NodeSet, SpectralRenderer, SpectralView};
    let mesh = Arc::new(generate::annulus(1, 4, 2, 3, NodeSet::GaussLobatto)?);
    let mut renderer = SpectralRenderer::new(gpu, mesh, &Colormap::viridis())?;
    let target = RenderTarget::new(gpu, "lost spectral", 64, 48, ColorFormat::Rgba8)
        .map_err(galerkin::spectral::SpectralError::device("target"))?;
    renderer.render(&target, &SpectralView::default())?;
    Ok(())
}

fn spacetime(gpu: &Gpu) -> Result<(), galerkin::spacetime::SpacetimeError> {
    use galerkin::spacetime::{generate, SpacetimeRenderer, SpacetimeView};
    let mesh = generate::pulses(200);
    let mut renderer = SpacetimeRenderer::from_mesh(gpu, &mesh, &Colormap::viridis())?;
    let target = RenderTarget::new(gpu, "lost spacetime", 64, 48, ColorFormat::Rgba8)
        .map_err(galerkin::spacetime::SpacetimeError::device("target"))?;
    let view = SpacetimeView::looking_at(renderer.data().summary(), 0.5 * mesh.time_range().1);
    renderer.render(&target, &view)?;
    Ok(())
}

fn fluid_particles(gpu: &Gpu) -> Result<(), galerkin::fluid::FluidError> {
    use galerkin::fluid::gpu::GpuParticles;
    use galerkin::fluid::particles::seed_particles;
    use galerkin::mesh::kuhn::kuhn_box;
    use galerkin::mesh::{Periodic, Topology};
    let mesh = kuhn_box(2, [6, 3, 0], [2.0, 1.0, 1.0])?;
    let topology = Topology::new(&mesh, Some(Periodic { axis: 0 }))?;
    let particles = seed_particles(&mesh, 50);
    let device = GpuParticles::new(gpu, &mesh, &topology, &particles)?;
    device.download(gpu)?;
    Ok(())
}

fn radiosity(gpu: &Gpu) -> Result<(), galerkin::radiosity::RadiosityError> {
    use galerkin::radiosity::form_factor::NearField;
    use galerkin::radiosity::gpu::GpuRadiosity;
    use galerkin::radiosity::{full_radiosity, SceneSpec};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let spec = SceneSpec::load(&root.join("scenes/radiosity/two_rooms_small.toml"))?;
    let scene = full_radiosity(&spec, &spec.defaults())?;
    let device = GpuRadiosity::new(gpu)?;
    device.form_factors(gpu, &scene.mesh, NearField::Regularised)?;
    Ok(())
}

fn premultiply(gpu: &Gpu) -> Result<(), galerkin::reduce::ReduceError> {
    galerkin::bench::reduce::premultiply_volume(200, 8, 3, Some(gpu), None)?;
    Ok(())
}

/// `f` injected into each capability's device work.
fn every_capability_fails_typed(f: Fault) {
    fails_typed("spectral render", f, spectral);
    fails_typed("spacetime render", f, spacetime);
    fails_typed("fluid device particles", f, fluid_particles);
    fails_typed("radiosity form factors on the device", f, radiosity);
    fails_typed("premultiplication on the device", f, premultiply);
}

#[test]
fn device_loss_reaches_the_caller_typed_from_every_capability() {
    every_capability_fails_typed(Fault::DeviceLost);
}

#[test]
fn out_of_memory_reaches_the_caller_typed_from_every_capability() {
    every_capability_fails_typed(Fault::OutOfMemory);
}

/// The trait's answers for the device layer's own error.
#[test]
fn a_device_error_answers_for_itself() {
    let e = GpuError::DeviceLost { during: "a test" };
    assert!(e.is_device_lost() && !e.is_out_of_memory());
    let e = GpuError::OutOfMemory { name: "x".into(), bytes: 8, detail: "none left".into() };
    assert!(e.is_out_of_memory() && !e.is_device_lost());
}
