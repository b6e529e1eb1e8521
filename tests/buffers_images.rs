//! Typed buffers and images: staged round trips across several staging chunks, partial
//! downloads, binding chunks on aligned offsets, colour-map textures, PNG/EXR files.

mod common;

use galerkin::gpu::{chunk_elements, vk, Buffer, MemoryKind, STAGING_CHUNK_BYTES};
use galerkin::render::{read_png_rgba8, write_exr_channels, write_exr_rgba, write_png_rgba8, Colormap};

#[test]
fn staged_round_trip_over_several_chunks_is_exact() {
    let gpu = common::gpu();
    // 2.5 staging chunks of f32, so both staging buffers are reused and the last is partial.
    let n = (STAGING_CHUNK_BYTES * 5 / 2 / 4) as usize + 3;
    let data = common::random_f32(n, 3);
    let b = Buffer::from_slice(&gpu, "round trip", &data, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    assert_eq!(b.download(&gpu).unwrap(), data);
    // Partial download and upload at an offset.
    let part = b.download_range(&gpu, galerkin::gpu::Chunk { first: 1000, len: 77 }).unwrap();
    assert_eq!(part, data[1000..1077]);
    b.upload(&gpu, 5, &[9.0, 8.0]).unwrap();
    let again = b.download_range(&gpu, galerkin::gpu::Chunk { first: 4, len: 4 }).unwrap();
    assert_eq!(again, [data[4], 9.0, 8.0, data[7]]);
}

#[test]
fn host_visible_buffers_map() {
    let gpu = common::gpu();
    let mut b =
        Buffer::<u32>::new(&gpu, "mapped", 16, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::CpuToGpu)
            .unwrap();
    b.mapped_mut().unwrap().copy_from_slice(&[3; 16]);
    assert_eq!(b.download(&gpu).unwrap(), vec![3; 16]);
    let g = Buffer::<u32>::new(&gpu, "device", 16, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
        .unwrap();
    assert!(
        g.mapped().is_none() || gpu.caps().memory_types.len() == 1,
        "device-only memory is not promised to map"
    );
}

#[test]
fn binding_chunks_are_aligned_and_cover_everything() {
    for (len, elem, max, align) in
        [(1000u64, 4u64, 256u64, 64u64), (12345, 12, 1 << 10, 16), (7, 4, 1 << 20, 256), (0, 4, 64, 16)]
    {
        let chunks = chunk_elements(len, elem, max, align);
        let mut next = 0;
        for c in &chunks {
            assert_eq!(c.first, next, "contiguous");
            assert_eq!((c.first * elem) % align, 0, "offset {} not aligned to {align}", c.first * elem);
            assert!(c.len * elem <= max.max(elem * align), "chunk too large");
            next += c.len;
        }
        assert_eq!(next, len);
    }
}

#[test]
fn colormap_textures_upload_and_ramps_load() {
    let gpu = common::gpu();
    for map in [Colormap::viridis(), Colormap::cool_warm(), Colormap::grey()] {
        assert_eq!(map.texels().len(), 256);
        let _texture = map.upload(&gpu).unwrap();
        // The ends of the ramp are its first and last texels.
        let first = map.texels()[0].map(|c| f64::from(c) / 255.0);
        assert!(map.sample(0.0).iter().zip(first).all(|(a, b)| (a - b).abs() < 1e-12));
    }
    // Viridis starts dark purple and ends yellow; cool-warm goes blue → red.
    assert_eq!(Colormap::viridis().texels()[0], [68, 1, 84, 255]);
    assert_eq!(Colormap::viridis().texels()[255], [253, 231, 37, 255]);
    let cw = Colormap::cool_warm();
    assert!(cw.texels()[0][2] > cw.texels()[0][0] && cw.texels()[255][0] > cw.texels()[255][2]);

    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");

    let dir = scratch.path().to_path_buf();
    let path = dir.join("ramp.png");
    write_png_rgba8(
        &path,
        3,
        2,
        &[255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 1, 2, 3, 255, 4, 5, 6, 255, 7, 8, 9, 255],
    )
    .unwrap();
    let ramp = Colormap::by_name(path.to_str().unwrap()).unwrap();
    assert_eq!(
        ramp.texels(),
        &[[1, 2, 3, 255], [4, 5, 6, 255], [7, 8, 9, 255]],
        "the middle row (row 1 of 2)"
    );
    let mid = ramp.sample(0.5);
    assert!((mid[0] - 4.0 / 255.0).abs() < 1e-12);
    write_png_rgba8(&path, 1, 1, &[0, 0, 0, 255]).unwrap();
    let err = Colormap::by_name(path.to_str().unwrap()).unwrap_err().to_string();
    assert!(err.contains("ramp.png") && err.contains("2 to 4096"), "{err}");
    assert!(Colormap::by_name("plasma-ish").unwrap_err().to_string().contains("viridis"));
}

#[test]
fn png_and_exr_files_round_trip_without_leftovers() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let rgba: Vec<u8> = (0..4 * 5 * 3).map(|i| (i * 7 % 256) as u8).collect();
    write_png_rgba8(&dir.join("a.png"), 5, 3, &rgba).unwrap();
    assert_eq!(read_png_rgba8(&dir.join("a.png")).unwrap(), (5, 3, rgba));

    let values: Vec<f32> = (0..4 * 4 * 2).map(|i| i as f32 * 0.25 - 3.0).collect();
    write_exr_rgba(&dir.join("v.exr"), 4, 2, &values).unwrap();
    let image = exr::prelude::read_first_rgba_layer_from_file(
        dir.join("v.exr"),
        |size, _| vec![[0f32; 4]; size.width() * size.height()],
        |px: &mut Vec<[f32; 4]>, pos, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.y() * 4 + pos.x()] = [r, g, b, a]
        },
    )
    .unwrap();
    let back: Vec<f32> = image.layer_data.channel_data.pixels.concat();
    assert_eq!(back, values);
    // Compressed: a constant 1920 × 1080 image (33 MB of floats) is a few hundred kB at most.
    let (w, h) = (1920u32, 1080u32);
    write_exr_rgba(&dir.join("flat.exr"), w, h, &vec![0.5f32; 4 * (w * h) as usize]).unwrap();
    let size = std::fs::metadata(dir.join("flat.exr")).unwrap().len();
    assert!(size < 1 << 20, "a constant EXR of {size} bytes");
    write_exr_channels(&dir.join("c.exr"), w, h, vec![("U", vec![f32::NAN; (w * h) as usize])]).unwrap();
    let size = std::fs::metadata(dir.join("c.exr")).unwrap().len();
    assert!(size < 1 << 20, "a constant one-channel EXR of {size} bytes");
    let names: Vec<_> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "temporary files left: {names:?}");
}
