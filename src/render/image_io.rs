//! PNG (8-bit sRGB RGBA) and EXR (32-bit float RGBA) files. Writers never leave a half-written
//! file behind and two writers of one name never share a temporary ([`crate::atomic_file`]).

use std::fs::File;
use std::io::{BufReader, BufWriter};
use std::path::Path;

use super::error::RenderError;
use crate::atomic_file::AtomicFile;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> RenderError + '_ {
    move |cause| RenderError::Io { path: path.to_path_buf(), cause }
}

/// Writes `rgba` (row-major from the top row, 4 bytes per pixel) as an 8-bit RGBA PNG.
pub fn write_png_rgba8(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), RenderError> {
    assert_eq!(rgba.len(), 4 * width as usize * height as usize, "PNG pixel buffer size");
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let mut file = AtomicFile::create(path).map_err(io(path))?;
    let err = |e: png::EncodingError| RenderError::Image { path: path.to_path_buf(), detail: e.to_string() };
    {
        let mut encoder = png::Encoder::new(BufWriter::new(file.file()), width, height);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(err)?;
        writer.write_image_data(rgba).map_err(err)?;
        writer.finish().map_err(err)?;
    }
    file.commit().map_err(io(path))
}

/// Reads a PNG as 8-bit RGBA (grey, RGB and 16-bit images are converted).
pub fn read_png_rgba8(path: &Path) -> Result<(u32, u32, Vec<u8>), RenderError> {
    let file = File::open(path).map_err(io(path))?;
    let mut decoder = png::Decoder::new(BufReader::new(file));
    decoder.set_transformations(
        png::Transformations::EXPAND | png::Transformations::STRIP_16 | png::Transformations::ALPHA,
    );
    let bad = |e: png::DecodingError| RenderError::Image { path: path.to_path_buf(), detail: e.to_string() };
    let mut reader = decoder.read_info().map_err(bad)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| RenderError::Image { path: path.to_path_buf(), detail: "image too large".into() })?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(bad)?;
    buf.truncate(info.buffer_size());
    let rgba = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::GrayscaleAlpha => {
            buf.chunks_exact(2).flat_map(|p| [p[0], p[0], p[0], p[1]]).collect()
        }
        other => {
            return Err(RenderError::Image {
                path: path.to_path_buf(),
                detail: format!("unexpected colour type {other:?} after expansion"),
            })
        }
    };
    Ok((info.width, info.height, rgba))
}

/// Writes `rgba` (row-major from the top, 4 floats per pixel) as a 32-bit float RGBA EXR:
/// the raw field values, for analysis without colour-map quantisation. ZIP-compressed
/// (lossless, 16 scan lines per block: every EXR reader supports it).
pub fn write_exr_rgba(path: &Path, width: u32, height: u32, rgba: &[f32]) -> Result<(), RenderError> {
    assert_eq!(rgba.len(), 4 * width as usize * height as usize, "EXR pixel buffer size");
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let w = width as usize;
    use exr::prelude::*;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let i = 4 * (y * w + x);
        (rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3])
    });
    let mut file = AtomicFile::create(path).map_err(io(path))?;
    Image::from_encoded_channels((w, height as usize), Encoding::SMALL_LOSSLESS, channels)
        .write()
        .to_buffered(BufWriter::new(&mut file))
        .map_err(|e| RenderError::Image { path: path.to_path_buf(), detail: e.to_string() })?;
    file.commit().map_err(io(path))
}

/// Writes named 32-bit float channels (each row-major from the top, `width × height` values)
/// as one EXR layer: raw values beside or instead of colour, for analysis (e.g. a spacetime
/// slice's `U`, `speed` and normal). ZIP-compressed; written whole or not at all.
pub fn write_exr_channels(
    path: &Path,
    width: u32,
    height: u32,
    channels: Vec<(&str, Vec<f32>)>,
) -> Result<(), RenderError> {
    use exr::prelude::*;
    let n = width as usize * height as usize;
    for (name, v) in &channels {
        assert_eq!(v.len(), n, "EXR channel {name} size");
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io(dir))?;
    }
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> =
        channels.into_iter().map(|(name, v)| AnyChannel::new(name, FlatSamples::F32(v))).collect();
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let mut file = AtomicFile::create(path).map_err(io(path))?;
    Image::from_layer(layer)
        .write()
        .to_buffered(BufWriter::new(&mut file))
        .map_err(|e| RenderError::Image { path: path.to_path_buf(), detail: e.to_string() })?;
    file.commit().map_err(io(path))
}

/// Channel `c` of RGBA8 pixels as floats in [0, 1]: an image's colour beside raw values in an
/// EXR file.
pub fn rgba8_channel(rgba: &[u8], c: usize) -> Vec<f32> {
    rgba.chunks_exact(4).map(|p| f32::from(p[c]) / 255.0).collect()
}

/// Channel `c` of RGBA32F pixels.
pub fn rgba32f_channel(rgba: &[f32], c: usize) -> Vec<f32> {
    rgba.chunks_exact(4).map(|p| p[c]).collect()
}
