//! Declared access (`galerkin::gpu::Access`): passes state what they read and write and the
//! recorder derives the barriers, with synchronization2 (`vkCmdPipelineBarrier2`) where the
//! device enabled it and Vulkan 1.0's barrier otherwise. Every test runs under the Khronos
//! validation layer with synchronization validation, which reports any hazard a missing or
//! wrong barrier leaves (see `validation.rs`'s canary), and fails on any message. Results are
//! checked against plain CPU computations, and the two barrier paths must agree bit for bit.

mod common;

use std::sync::Arc;

use galerkin::gpu::{vk, Access, Buffer, Image, ImageDesc, ImageResource, MemoryKind};
use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::generate::quad_grid;
use galerkin::spectral::{NodeSet, SpectralRenderer, SpectralView, View2d};

const PATHS: [bool; 2] = [true, false];

/// A chain of transfers with no barrier written by hand: fill → copy → copy → copy back over
/// the first → download. Each step reads what the last wrote (read-after-write) and the last
/// overwrites what an earlier step read (write-after-read).
#[test]
fn transfer_chains_are_ordered_by_their_declarations() {
    for sync2 in PATHS {
        let gpu = common::gpu_with(|d| d.synchronization2 = sync2);
        assert_eq!(gpu.caps().synchronization2, sync2 && gpu.caps().api_version.1 >= 3);
        let make = |name| {
            Buffer::<u32>::new(&gpu, name, 4096, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
                .unwrap()
        };
        let (a, b, c) = (make("a"), make("b"), make("c"));
        gpu.run(|rec| {
            rec.fill_buffer(&a, 7);
            rec.copy_buffer(&a, 0, &b, 0, 4096);
            rec.fill_buffer(&a, 9);
            rec.copy_buffer(&b, 0, &c, 0, 2048);
            rec.copy_buffer(&a, 2048, &c, 2048, 2048);
        })
        .unwrap();
        let got = c.download(&gpu).unwrap();
        assert!(got[..2048].iter().all(|&v| v == 7), "sync2 {sync2}: the first half is the fill of 7");
        assert!(got[2048..].iter().all(|&v| v == 9), "sync2 {sync2}: the second half is the fill of 9");
    }
}

/// Layout-tracked image operations: texels copied into an image, blitted at twice the size
/// into a second, read back; compared with nearest-texel upscaling done on the CPU. The
/// layouts (UNDEFINED → TRANSFER_DST → TRANSFER_SRC, …) are the recorder's business.
#[test]
fn image_operations_track_layouts() {
    for sync2 in PATHS {
        let gpu = common::gpu_with(|d| d.synchronization2 = sync2);
        let (w, h) = (5u32, 3u32);
        let texels: Vec<u8> = (0..w * h * 4).map(|i| (i * 37 % 251) as u8).collect();
        let mut small =
            Image::new(&gpu, "small", ImageDesc::color_target(w, h, vk::Format::R8G8B8A8_UNORM)).unwrap();
        let mut large =
            Image::new(&gpu, "large", ImageDesc::color_target(2 * w, 2 * h, vk::Format::R8G8B8A8_UNORM))
                .unwrap();
        let source =
            Buffer::<u8>::from_slice(&gpu, "texels", &texels, vk::BufferUsageFlags::empty()).unwrap();
        let out = Buffer::<u8>::new(
            &gpu,
            "out",
            u64::from(16 * w * h),
            vk::BufferUsageFlags::empty(),
            MemoryKind::GpuToCpu,
        )
        .unwrap();
        gpu.run(|rec| {
            let extent = small.extent();
            rec.copy_buffer_to_image(&source, &mut small, vk::Offset2D::default(), extent);
            let extent = large.extent();
            rec.blit(&small, &mut large, extent);
            rec.copy_image_to_buffer(&large, &out);
            rec.access(&out, Access::HOST_READ);
        })
        .unwrap();
        let got = out.mapped().unwrap();
        for y in 0..2 * h {
            for x in 0..2 * w {
                for c in 0..4 {
                    let want = texels[((y / 2 * w + x / 2) * 4 + c) as usize];
                    let at = ((y * 2 * w + x) * 4 + c) as usize;
                    assert_eq!(got[at], want, "sync2 {sync2}: texel ({x}, {y}) channel {c}");
                }
            }
        }
        // A second recording reads the image in the layout the first left it in.
        let again = Buffer::<u8>::new(
            &gpu,
            "again",
            u64::from(4 * w * h),
            vk::BufferUsageFlags::empty(),
            MemoryKind::GpuToCpu,
        )
        .unwrap();
        gpu.run(|rec| {
            rec.copy_image_to_buffer(&small, &again);
            rec.access(&again, Access::HOST_READ);
        })
        .unwrap();
        assert_eq!(again.mapped().unwrap(), &texels[..], "sync2 {sync2}");
    }
}

/// A pass with compute before its draw (the spectral elements' tessellation or proxies, the
/// draw, the readback): the same pixels on both barrier paths, and no validation message.
#[test]
fn both_barrier_paths_render_the_same_pixels() {
    let mesh = Arc::new(quad_grid(4, 3, 0.2, 6, NodeSet::GaussLobatto).unwrap());
    let mut frames = Vec::new();
    for sync2 in PATHS {
        let gpu = common::gpu_with(|d| d.synchronization2 = sync2);
        let mut spectral = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let target = RenderTarget::new(&gpu, "frame", 96, 64, ColorFormat::Rgba8).unwrap();
        let view =
            SpectralView { view: Some(View2d::fit(&mesh, 96, 64)), edges: true, ..SpectralView::default() };
        // Twice on one target: the second frame's writes wait for the first frame's reads.
        let first = spectral.render(&target, &view).unwrap();
        let second = spectral.render(&target, &view).unwrap();
        assert_eq!(first, second, "sync2 {sync2}: the same frame twice");
        let Pixels::Rgba8(p) = second else { panic!("RGBA8 target") };
        frames.push(p);
    }
    assert_eq!(frames[0], frames[1], "synchronization2 and Vulkan 1.0 barriers draw the same pixels");
}

/// The image trait's description of an engine image.
#[test]
fn images_describe_themselves() {
    let gpu = common::gpu();
    let image =
        Image::new(&gpu, "i", ImageDesc::color_target(7, 3, vk::Format::R32G32B32A32_SFLOAT)).unwrap();
    assert_eq!(ImageResource::extent(&image), vk::Extent2D { width: 7, height: 3 });
    assert_eq!(ImageResource::format(&image), vk::Format::R32G32B32A32_SFLOAT);
    assert_eq!(ImageResource::aspect(&image), vk::ImageAspectFlags::COLOR);
}
