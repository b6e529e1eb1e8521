//! Drawing inside a host's dynamic rendering (`RenderPass::dynamic` + `DrawTarget`, Vulkan 1.3
//! `vkCmdBeginRendering`): the host begins rendering on its own BGRA colour image and D32
//! depth image (cleared grey and far), galerkin's spectral elements draw in a viewport away
//! from the corner, and the result must be what the same renderer draws offscreen — covered
//! pixels bit for bit, uncovered ones the host's clear, nothing outside the viewport — with
//! synchronization validation on. The depth attachment is the host's: its clear value is
//! what galerkin's depth test starts from. Then what is refused: a colour format galerkin does
//! not write, and a spectral draw in rendering without depth.

mod common;

use std::sync::Arc;

use common::host::{differing_from_offscreen, HostCommands};
use galerkin::gpu::{
    vk, Access, Buffer, GpuError, Image, ImageDesc, MemoryKind, Recorder, RenderPass, Viewport,
};
use galerkin::render::{ColorFormat, Colormap, Draw, DrawTarget, Pixels, RenderTarget};
use galerkin::spectral::generate::quad_grid;
use galerkin::spectral::{NodeSet, SpectralError, SpectralRenderer, SpectralView, View2d};

const FB: vk::Extent2D = vk::Extent2D { width: 200, height: 150 };
const VIEWPORT: Viewport = Viewport { x: 41, y: 17, width: 120, height: 90 };
/// The host's clear colour, exactly representable in 8 bits (100 / 255).
const GREY: u8 = 100;

/// Records `pre` (outside rendering) and `draw` (inside the host's dynamic rendering on its
/// BGRA colour and D32 depth images, cleared grey and far) into the host's command buffer,
/// submits, and returns the colour image as RGBA8.
fn host_frame(
    gpu: &galerkin::gpu::Gpu,
    pre: impl FnOnce(&mut Recorder<'_>, DrawTarget<'_>),
    draw: impl FnOnce(&mut Recorder<'_>, DrawTarget<'_>),
    viewport: Viewport,
) -> Vec<u8> {
    let bgra = vk::Format::B8G8R8A8_UNORM;
    let d32 = vk::Format::D32_SFLOAT;
    let mut colour =
        Image::new(gpu, "host colour", ImageDesc::color_target(FB.width, FB.height, bgra)).unwrap();
    let mut depth = Image::new(gpu, "host depth", ImageDesc::depth_target(FB.width, FB.height, d32)).unwrap();
    let pass = RenderPass::dynamic(gpu, bgra, Some(d32)).unwrap();
    assert!(pass.is_dynamic() && pass.is_host());
    let target = DrawTarget::new(&pass, viewport).unwrap();
    let readback = Buffer::<u8>::new(
        gpu,
        "host readback",
        u64::from(4 * FB.width * FB.height),
        vk::BufferUsageFlags::empty(),
        MemoryKind::GpuToCpu,
    )
    .unwrap();
    let host = HostCommands::new(gpu);
    // SAFETY: the host's buffer is recording on this device, used by this thread only, and the
    // Recording is kept until its fence was waited for.
    let mut rec = unsafe { Recorder::from_host(gpu, host.cmd) };
    pre(&mut rec, target);
    // The host's attachments go to their layouts through the recorder's tracked transitions.
    let fragment_tests =
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS;
    let colour_write = Access {
        stages: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
        access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
    };
    let depth_write = Access {
        stages: fragment_tests,
        access: vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
    };
    rec.transition(&mut colour, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, colour_write);
    rec.transition(&mut depth, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, depth_write);
    let g = f32::from(GREY) / 255.0;
    let colour_attachment = [vk::RenderingAttachmentInfo::default()
        .image_view(colour.view())
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [g, g, g, 1.0] } })];
    let depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(depth.view())
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
    let rendering = vk::RenderingInfo::default()
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: FB })
        .layer_count(1)
        .color_attachments(&colour_attachment)
        .depth_attachment(&depth_attachment);
    // SAFETY: the host's own dynamic rendering on its images, in the layouts just set.
    unsafe { gpu.device().cmd_begin_rendering(host.cmd, &rendering) };
    draw(&mut rec, target);
    // SAFETY: ends the rendering begun above, which wrote the colour image in
    // COLOR_ATTACHMENT_OPTIMAL; the recorder then moves it to TRANSFER_SRC for the copy.
    unsafe {
        gpu.device().cmd_end_rendering(host.cmd);
        rec.image_written_externally(&colour, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, colour_write);
    }
    colour.record_copy_to_buffer(&mut rec, &readback);
    let recording = rec.finish();
    host.submit_and_wait();
    drop(recording);
    // The host's attachment is BGRA: swap to RGBA.
    let mut got = readback.mapped().unwrap().to_vec();
    for px in got.chunks_exact_mut(4) {
        px.swap(0, 2);
    }
    got
}

#[test]
fn spectral_elements_draw_inside_a_host_dynamic_rendering_in_its_viewport() {
    let gpu = common::gpu();
    assert!(gpu.caps().dynamic_rendering, "lavapipe is a Vulkan 1.3 device: dynamic rendering is enabled");
    let mesh = Arc::new(quad_grid(4, 3, 0.2, 6, NodeSet::GaussLobatto).unwrap());
    let mut spectral = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let view = SpectralView {
        view: Some(View2d::fit(&mesh, VIEWPORT.width, VIEWPORT.height)),
        edges: true,
        ..SpectralView::default()
    };
    let spectral = std::cell::RefCell::new(&mut spectral);
    let got = host_frame(
        &gpu,
        |rec, target| spectral.borrow_mut().record_prepass(rec, target, &view).unwrap(),
        |rec, target| spectral.borrow_mut().record_draw_into(rec, target, &view).unwrap(),
        VIEWPORT,
    );
    let offscreen =
        RenderTarget::new(&gpu, "reference", VIEWPORT.width, VIEWPORT.height, ColorFormat::Rgba8).unwrap();
    let Pixels::Rgba8(want) = spectral.borrow_mut().render(&offscreen, &view).unwrap() else {
        panic!("RGBA8 target")
    };
    let (covered, differing) = differing_from_offscreen(&got, &want, FB, VIEWPORT, GREY);
    assert!(covered > 5_000, "the elements cover most of the viewport: {covered}");
    assert_eq!(differing, 0, "pixels that differ from the offscreen render or the host's clear");
}

/// A spacetime slice drawn in the host's dynamic rendering, its viewport at the corner (where
/// its rasterisation is the offscreen render's: a spacetime draw interpolated across
/// triangles can move by one 8-bit step where a viewport's offset changes the rounding).
#[test]
fn a_spacetime_slice_draws_inside_a_host_dynamic_rendering() {
    use galerkin::spacetime::{generate, SpacetimeRenderer, SpacetimeView};
    let gpu = common::gpu();
    let mesh = generate::pulses(400);
    let mut renderer = SpacetimeRenderer::from_mesh(&gpu, &mesh, &Colormap::viridis()).unwrap();
    let corner = Viewport { x: 0, y: 0, width: 120, height: 90 };
    let view = SpacetimeView::looking_at(renderer.data().summary(), 0.5 * mesh.time_range().1);
    let pass = RenderPass::dynamic(&gpu, vk::Format::B8G8R8A8_UNORM, Some(vk::Format::D32_SFLOAT)).unwrap();
    // Slices at the view's time (engine submission) and fixes the colour range.
    let u_max = renderer.u_max_for(DrawTarget::new(&pass, corner).unwrap(), &view).unwrap();
    let renderer = std::cell::RefCell::new(&mut renderer);
    let got = host_frame(
        &gpu,
        |_, _| {},
        |rec, target| renderer.borrow_mut().record_draw_into(rec, target, &view, u_max).unwrap(),
        corner,
    );
    let offscreen =
        RenderTarget::new(&gpu, "reference", corner.width, corner.height, ColorFormat::Rgba8).unwrap();
    let view = SpacetimeView { u_max: Some(u_max), ..view };
    let Pixels::Rgba8(want) = renderer.borrow_mut().render(&offscreen, &view).unwrap() else {
        panic!("RGBA8 target")
    };
    let (covered, differing) = differing_from_offscreen(&got, &want, FB, corner, GREY);
    assert!(covered > 2_000, "the slice covers much of the viewport: {covered}");
    assert_eq!(differing, 0, "pixels that differ from the offscreen render or the host's clear");
}

#[test]
fn dynamic_rendering_galerkin_cannot_draw_in_is_refused() {
    let gpu = common::gpu();
    for format in [vk::Format::B8G8R8A8_SRGB, vk::Format::R16G16B16A16_SFLOAT] {
        match RenderPass::dynamic(&gpu, format, None) {
            Err(GpuError::Unsupported(m)) => assert!(m.contains(&format!("{format:?}")), "{m}"),
            other => panic!("{format:?} accepted: {other:?}"),
        }
    }
    let pass = RenderPass::dynamic(&gpu, vk::Format::R8G8B8A8_UNORM, None).unwrap();
    let mesh = Arc::new(quad_grid(2, 2, 0.0, 3, NodeSet::GaussLobatto).unwrap());
    let mut spectral = SpectralRenderer::new(&gpu, mesh, &Colormap::viridis()).unwrap();
    let host = HostCommands::new(&gpu);
    // SAFETY: as in the first test; nothing is recorded, the buffer is never submitted.
    let mut rec = unsafe { Recorder::from_host(&gpu, host.cmd) };
    let target = DrawTarget::new(&pass, VIEWPORT).unwrap();
    match spectral.record_draw_into(&mut rec, target, &SpectralView::default()) {
        Err(SpectralError::Device { cause: GpuError::Unsupported(m), .. }) => {
            assert!(m.contains("depth attachment"), "{m}")
        }
        other => panic!("rendering without depth was accepted: {other:?}"),
    }
    drop(rec.finish());
    // A framebuffer cannot be made for a host's dynamic rendering.
    let image = Image::new(&gpu, "c", ImageDesc::color_target(8, 8, vk::Format::R8G8B8A8_UNORM)).unwrap();
    assert!(galerkin::gpu::Framebuffer::new(&gpu, &pass, &[&image], vk::Extent2D { width: 8, height: 8 })
        .is_err());
}

/// Draws `drawable` through the one draw trait (`galerkin::render::Draw`) into the host's
/// dynamic rendering in `viewport`, and into galerkin's offscreen target of the viewport's
/// size with `offscreen` (a renderer of the same content made for that target's pass);
/// returns the number of covered pixels after checking that none differs.
fn host_and_offscreen_agree<D: Draw>(
    gpu: &galerkin::gpu::Gpu,
    host: &mut D,
    offscreen: &mut D,
    reference: &RenderTarget,
    view: &D::View<'_>,
    viewport: Viewport,
) -> usize {
    let host = std::cell::RefCell::new(host);
    let got = host_frame(
        gpu,
        |rec, target| host.borrow_mut().record_prepass(rec, target, view).unwrap_or_else(|e| panic!("{e}")),
        |rec, target| host.borrow_mut().record_draw_into(rec, target, view).unwrap_or_else(|e| panic!("{e}")),
        viewport,
    );
    let Pixels::Rgba8(want) =
        reference.draw(gpu, offscreen, view, [0.0, 0.0, 0.0, 1.0]).unwrap_or_else(|e| panic!("{e}"))
    else {
        panic!("RGBA8 target")
    };
    let (covered, differing) = differing_from_offscreen(&got, &want, FB, viewport, GREY);
    assert_eq!(differing, 0, "pixels that differ from the offscreen render or the host's clear");
    covered
}

/// Fluid cells (a 2D triangle stream with per-cell speeds) and radiosity faces (a lit scene)
/// through the same trait as the spectral and spacetime draws, inside a host's dynamic
/// rendering, pixel for pixel against the offscreen renders; and a renderer made for one
/// render pass refuses a target of another.
#[test]
fn fluid_and_radiosity_draw_inside_a_host_dynamic_rendering() {
    use galerkin::fluid::render::{
        CellVertex, DrawStyle, FluidRenderer, FluidView, Output as FluidOutput, Projection, View2d,
    };
    use galerkin::radiosity::render::{Output as SceneOutput, SceneRenderer, SceneVertex, SceneView};
    use galerkin::render::Camera;
    let gpu = common::gpu();
    let corner = Viewport { x: 0, y: 0, width: 120, height: 90 };
    let dynamic =
        RenderPass::dynamic(&gpu, vk::Format::B8G8R8A8_UNORM, Some(vk::Format::D32_SFLOAT)).unwrap();
    let reference =
        RenderTarget::new(&gpu, "reference", corner.width, corner.height, ColorFormat::Rgba8).unwrap();

    // Eight triangles of a 2×2 grid of squares, each its own cell and speed.
    let mut cells = Vec::new();
    for (k, (x, y)) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].into_iter().enumerate() {
        let corners = [[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
        for (t, tri) in [[0, 1, 2], [0, 2, 3]].into_iter().enumerate() {
            let cell = (2 * k + t) as u32;
            for i in tri {
                let [px, py]: [f32; 2] = corners[i];
                cells.push(CellVertex { position: [px, py, 0.0], value: 0.1 * (cell + 1) as f32, cell });
            }
        }
    }
    let speeds: Vec<f64> = (0..8).map(|c| 0.1 * f64::from(c + 1)).collect();
    let style = DrawStyle {
        colormap: Colormap::viridis(),
        range: (0.0, 1.0),
        log: false,
        colour_cells: true,
        sprite_px: 0.0,
    };
    let fluid = |pass: &RenderPass| {
        let mut r =
            FluidRenderer::new(&gpu, pass, FluidOutput::Colour, &style.colormap, cells.len() / 3, 8).unwrap();
        r.update(&cells, &speeds).unwrap();
        r
    };
    let projection =
        Projection::Plane(View2d::fit([0.0, 0.0], [2.0, 2.0], (corner.width, corner.height), 0.05));
    let view = FluidView { projection, style: &style, particles: None };
    let (mut host, mut offscreen) = (fluid(&dynamic), fluid(reference.render_pass()));
    let covered = host_and_offscreen_agree(&gpu, &mut host, &mut offscreen, &reference, &view, corner);
    assert!(covered > 5_000, "the cells cover most of the viewport: {covered}");

    // A room's wall: two quads facing the camera, both windings (back faces are culled).
    let quad = |x0: f32, x1: f32, radiance: [f32; 3], face: u32| {
        let (a, b, c, d) = ([x0, 0.0, 0.0], [x1, 0.0, 0.0], [x1, 0.0, 1.0], [x0, 0.0, 1.0]);
        let v = |position| SceneVertex { position, radiance, face };
        vec![v(a), v(b), v(c), v(a), v(c), v(d), v(a), v(c), v(b), v(a), v(d), v(c)]
    };
    let mut faces = quad(-1.0, 0.0, [0.8, 0.3, 0.1], 0);
    faces.extend(quad(0.0, 1.0, [0.1, 0.4, 0.9], 1));
    let scene = |pass: &RenderPass| {
        let mut r = SceneRenderer::new(&gpu, pass, SceneOutput::Colour, faces.len() / 3).unwrap();
        r.update(&faces).unwrap();
        r
    };
    let camera = Camera {
        eye: [0.0, -2.5, 0.5],
        target: [0.0, 0.0, 0.5],
        up: [0.0, 0.0, 1.0],
        fov_y_degrees: 60.0,
        near: 0.05,
        far: 50.0,
    };
    let view = SceneView { camera, exposure: 1.0 };
    let (mut host, mut offscreen) = (scene(&dynamic), scene(reference.render_pass()));
    let covered = host_and_offscreen_agree(&gpu, &mut host, &mut offscreen, &reference, &view, corner);
    // The wall (2 × 1 at 2.5 from a 60° camera) spans about 62 × 31 of the 120 × 90 pixels.
    assert!(covered > 1_500, "the wall covers its share of the viewport: {covered}");

    // Pipelines made for the dynamic rendering cannot draw in galerkin's own pass.
    let other = reference.draw(&gpu, &mut host, &view, [0.0; 4]);
    match other {
        Err(e) => assert!(e.to_string().contains("were not made for"), "{e}"),
        Ok(_) => panic!("a renderer drew into a render pass of another class"),
    }
}
