//! Drawing inside a host's own render pass (`RenderPass::from_host` + `DrawTarget`): the
//! spectral renderer draws into a host's BGRA framebuffer, in a viewport away from its corner,
//! and must show exactly what it shows offscreen — covered pixels bit for bit (planar elements
//! take their world point from the pixel centre relative to the viewport's corner, exact in
//! f32), uncovered ones the host's clear, nothing outside the viewport; colour formats galerkin
//! does not write are refused, as are spectral draws in a pass without depth.

mod common;

use std::sync::Arc;

use common::host::{differing_from_offscreen, HostCommands, HostPass};
use galerkin::gpu::{
    vk, Access, Buffer, GpuError, HostRenderPass, Image, ImageDesc, MemoryKind, Recorder, RenderPass,
    Viewport,
};
use galerkin::render::{ColorFormat, Colormap, DrawTarget, Pixels, RenderTarget};
use galerkin::spectral::generate::quad_grid;
use galerkin::spectral::{NodeSet, SpectralError, SpectralRenderer, SpectralView, View2d};

const FB: vk::Extent2D = vk::Extent2D { width: 200, height: 150 };
const VIEWPORT: Viewport = Viewport { x: 37, y: 11, width: 120, height: 90 };
/// The host's clear colour, exactly representable in 8 bits (100 / 255).
const GREY: u8 = 100;

fn host_colour(gpu: &galerkin::gpu::Gpu, format: vk::Format) -> Image {
    Image::new(gpu, "host colour", ImageDesc::color_target(FB.width, FB.height, format)).unwrap()
}

#[test]
fn spectral_elements_draw_inside_a_host_render_pass_in_its_viewport() {
    let gpu = common::gpu();
    let bgra = vk::Format::B8G8R8A8_UNORM;
    let colour = host_colour(&gpu, bgra);
    let depth =
        Image::new(&gpu, "host depth", ImageDesc::depth_target(FB.width, FB.height, vk::Format::D32_SFLOAT))
            .unwrap();
    let host_pass =
        HostPass::new(&gpu, (colour.raw(), bgra), Some((depth.raw(), vk::Format::D32_SFLOAT)), FB);
    // SAFETY: a live render pass of this device whose subpass 0 has one single-sampled BGRA
    // colour attachment and a D32 depth attachment; it outlives the renderer's use of it.
    let pass = unsafe {
        RenderPass::from_host(
            &gpu,
            HostRenderPass {
                raw: host_pass.raw,
                subpass: 0,
                color_format: bgra,
                depth_format: Some(vk::Format::D32_SFLOAT),
            },
        )
    }
    .unwrap();
    let target = DrawTarget::new(&pass, VIEWPORT).unwrap();
    assert_eq!(target.format(), ColorFormat::Rgba8);
    let mesh = Arc::new(quad_grid(4, 3, 0.2, 6, NodeSet::GaussLobatto).unwrap());
    let mut spectral = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let view = SpectralView {
        view: Some(View2d::fit(&mesh, VIEWPORT.width, VIEWPORT.height)),
        edges: true,
        ..SpectralView::default()
    };
    let readback = Buffer::<u8>::new(
        &gpu,
        "host readback",
        u64::from(4 * FB.width * FB.height),
        vk::BufferUsageFlags::empty(),
        MemoryKind::GpuToCpu,
    )
    .unwrap();
    let host = HostCommands::new(&gpu);
    // SAFETY: the host's buffer is recording on this device, used by this thread only, and the
    // Recording is kept until its fence was waited for.
    let mut rec = unsafe { Recorder::from_host(&gpu, host.cmd) };
    spectral.record_prepass(&mut rec, target, &view).unwrap();
    let g = f32::from(GREY) / 255.0;
    // SAFETY: outside any render pass, then inside the host's.
    unsafe { host_pass.begin(host.cmd, [g, g, g, 1.0]) };
    spectral.record_draw_into(&mut rec, target, &view).unwrap();
    // SAFETY: inside the host's pass; it leaves the colour image in TRANSFER_SRC_OPTIMAL, last
    // written as a colour attachment (the recorder adds the barrier to the copy).
    unsafe {
        host_pass.end(host.cmd);
        let written = Access {
            stages: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        };
        rec.image_written_externally(&colour, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, written);
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

    let offscreen =
        RenderTarget::new(&gpu, "reference", VIEWPORT.width, VIEWPORT.height, ColorFormat::Rgba8).unwrap();
    let Pixels::Rgba8(want) = spectral.render(&offscreen, &view).unwrap() else { panic!("RGBA8 target") };
    let (covered, differing) = differing_from_offscreen(&got, &want, FB, VIEWPORT, GREY);
    assert!(covered > 5_000, "the elements cover most of the viewport: {covered}");
    assert_eq!(differing, 0, "pixels that differ from the offscreen render or the host's clear");
}

#[test]
fn host_attachments_galerkin_does_not_write_and_passes_without_depth_are_refused() {
    let gpu = common::gpu();
    for format in [vk::Format::R8G8B8A8_SRGB, vk::Format::B8G8R8A8_SRGB, vk::Format::R16G16B16A16_SFLOAT] {
        let colour = host_colour(&gpu, format);
        let host_pass = HostPass::new(&gpu, (colour.raw(), format), None, FB);
        // SAFETY: a live single-subpass render pass of this device with that colour format.
        let refused = unsafe {
            RenderPass::from_host(
                &gpu,
                HostRenderPass { raw: host_pass.raw, subpass: 0, color_format: format, depth_format: None },
            )
        };
        match refused {
            Err(GpuError::Unsupported(m)) => assert!(m.contains(&format!("{format:?}")), "{m}"),
            other => panic!("{format:?} accepted: {other:?}"),
        }
    }
    let rgba = vk::Format::R8G8B8A8_UNORM;
    let colour = host_colour(&gpu, rgba);
    let host_pass = HostPass::new(&gpu, (colour.raw(), rgba), None, FB);
    // SAFETY: as above, RGBA8 without depth.
    let pass = unsafe {
        RenderPass::from_host(
            &gpu,
            HostRenderPass { raw: host_pass.raw, subpass: 0, color_format: rgba, depth_format: None },
        )
    }
    .unwrap();
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
        other => panic!("a pass without depth was accepted: {other:?}"),
    }
    drop(rec.finish());
    // An empty viewport is refused too.
    assert!(DrawTarget::new(&pass, Viewport { x: 0, y: 0, width: 0, height: 10 }).is_err());
}
