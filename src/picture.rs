//! A rendered picture as a file, the one way every capability writes one: PNG is the colour
//! picture (with a title and a colour bar beside it where the capability shows a scalar, as
//! ParaView's and GLVis's scalar bars do), EXR is data — the colour as float R, G, B and the
//! raw per-pixel values each capability names (the value, reference coordinates, the element),
//! NaN where nothing was drawn. The format comes from the file name's extension.

use std::path::{Path, PathBuf};

use crate::plot::{picture_with_colour_bar, ColourBar, PlotError};
use crate::render::{rgba32f_channel, rgba8_channel, write_exr_channels, write_png_rgba8, RenderError};

/// An output picture's format, from its file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB colour (with a legend where the capability draws one).
    Png,
    /// Float channels: the colour and the raw values the capability lists.
    Exr,
}

impl ImageFormat {
    /// The format of `path` by its extension (case-insensitive), if it is one we write.
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension().and_then(|e| e.to_str())?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(Self::Png),
            "exr" => Some(Self::Exr),
            _ => None,
        }
    }
}

/// Why a picture could not be written; the message names the file.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// Neither `.png` nor `.exr`.
    #[error("{0}: the image format comes from the extension: .png or .exr")]
    Format(PathBuf),
    /// Writing the PNG or EXR failed.
    #[error(transparent)]
    Image(#[from] RenderError),
    /// Drawing the legend failed (e.g. no font).
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// The format `path` is written in, or [`PictureError::Format`] naming it (checked before any
/// rendering).
pub fn format_of(path: &Path) -> Result<ImageFormat, PictureError> {
    ImageFormat::of(path).ok_or_else(|| PictureError::Format(path.to_path_buf()))
}

/// The picture size every `render` and viewer window uses unless `--size` says otherwise
/// (WIDTH, HEIGHT): one default across capabilities; a 2D fluid run or a planar mesh is fitted
/// into it, keeping its aspect.
pub const DEFAULT_SIZE: (u32, u32) = (1280, 720);

/// The legend of a PNG picture: a title above it and a colour bar beside it.
pub struct Legend<'a> {
    /// The title (data set, field, time).
    pub title: String,
    /// The colour bar (map, range, log, label).
    pub bar: ColourBar<'a>,
}

/// A float channel of an EXR picture: its name and its values, one per pixel, row-major.
pub type Channel = (&'static str, Vec<f32>);

/// Writes the colour picture `rgba` (8-bit, `size`) as PNG, with `legend` beside it when given.
pub fn write_png(
    path: &Path,
    size: (u32, u32),
    rgba: &[u8],
    legend: Option<&Legend<'_>>,
) -> Result<(), PictureError> {
    match legend {
        Some(l) => picture_with_colour_bar(rgba, size, &l.bar, &l.title, path)?,
        None => write_png_rgba8(path, size.0, size.1, rgba)?,
    }
    Ok(())
}

/// Writes an EXR of `channels`, after the colour picture `colour` as float R, G, B when given.
pub fn write_exr(
    path: &Path,
    size: (u32, u32),
    colour: Option<&[u8]>,
    channels: Vec<Channel>,
) -> Result<(), PictureError> {
    let mut named: Vec<Channel> = match colour {
        Some(rgba) => (0..3).map(|c| (["R", "G", "B"][c], rgba8_channel(rgba, c))).collect(),
        None => Vec::new(),
    };
    named.extend(channels);
    write_exr_channels(path, size.0, size.1, named)?;
    Ok(())
}

/// The channels of a float RGBA image `raw`, named `names` in order (at most four).
pub fn float_channels(raw: &[f32], names: &[&'static str]) -> Vec<Channel> {
    names.iter().enumerate().map(|(c, name)| (*name, rgba32f_channel(raw, c))).collect()
}

/// A named channel computed from each pixel's four floats.
pub type PixelChannel = (&'static str, fn(&[f32]) -> f32);

/// The channels of float RGBA pixels computed by `channels`' functions of each pixel.
pub fn mapped_channels(raw: &[f32], channels: &[PixelChannel]) -> Vec<Channel> {
    channels.iter().map(|(name, f)| (*name, raw.chunks_exact(4).map(f).collect())).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_come_from_the_extension() {
        assert_eq!(ImageFormat::of(Path::new("x.Png")), Some(ImageFormat::Png));
        assert_eq!(ImageFormat::of(Path::new("a/b.EXR")), Some(ImageFormat::Exr));
        assert_eq!(ImageFormat::of(Path::new("a.txt")), None);
        assert_eq!(ImageFormat::of(Path::new("a")), None);
        let e = format_of(Path::new("out/a.txt")).expect_err("not a picture format").to_string();
        assert!(e.contains("out/a.txt") && e.contains(".png or .exr"), "{e}");
    }

    #[test]
    fn channels_are_taken_per_pixel_in_order() {
        let raw = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let c = float_channels(&raw, &["a", "b"]);
        assert_eq!(c[0], ("a", vec![1.0, 5.0]));
        assert_eq!(c[1], ("b", vec![2.0, 6.0]));
        let m = mapped_channels(&raw, &[("sum", |p| p[0] + p[3])]);
        assert_eq!(m[0], ("sum", vec![5.0, 13.0]));
    }
}
