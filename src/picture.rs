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

/// What is drawn over a PNG picture besides the data (`--outline`, `--axes`; issue 50): the
/// edges of the data's bounding box, and an axis triad in the lower left corner showing where
/// +x (red), +y (green) and +z (blue) point. EXR files hold data only and get neither.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Overlay {
    /// The bounding box's twelve edges (a planar view: its rectangle), in grey.
    pub outline: bool,
    /// The axis triad.
    pub axes: bool,
}

/// What a PNG shows besides the data: its legend's title (`None`: no legend) and the overlay.
#[derive(Clone, Copy, Debug, Default)]
pub struct Decor<'a> {
    /// The title above the picture; with it comes the colour bar beside it.
    pub title: Option<&'a str>,
    /// The outline and axis triad drawn over the picture.
    pub overlay: Overlay,
}

/// How world points land on a picture's pixels (x right, y down), for [`draw_overlay`].
#[derive(Clone, Copy, Debug)]
pub enum Projector<'a> {
    /// A perspective camera ([`crate::render::Camera::project`]).
    Camera(&'a crate::render::Camera),
    /// A planar view from above: the world (x, y) at the picture's centre and the world size
    /// of a pixel (z is ignored).
    Plane {
        /// World (x, y) at the centre of the picture.
        centre: [f64; 2],
        /// World units per pixel.
        pixel_size: f64,
    },
}

impl Projector<'_> {
    /// Pixel coordinates of `p` in a picture of `size`; `None` behind the camera.
    pub fn project(&self, p: [f64; 3], size: (u32, u32)) -> Option<(f64, f64)> {
        match self {
            Projector::Camera(camera) => {
                let aspect = f64::from(size.0) / f64::from(size.1.max(1));
                let clip = camera.view_proj(aspect) * glam::DVec4::new(p[0], p[1], p[2], 1.0);
                (clip.w > 1e-12).then(|| camera.project(glam::DVec3::from_array(p), size.0, size.1))
            }
            Projector::Plane { centre, pixel_size } => Some((
                0.5 * f64::from(size.0) + (p[0] - centre[0]) / pixel_size,
                0.5 * f64::from(size.1) - (p[1] - centre[1]) / pixel_size,
            )),
        }
    }
}

/// Draws `overlay` over the picture `rgba` of `size` in place: the box [`lo`, `hi`]'s edges and
/// the axis triad, projected by `projector` (`name` stands for the file in errors). An edge with
/// an end behind the camera is left out; an axis seen end-on is left out of the triad.
pub fn draw_overlay(
    rgba: &mut [u8],
    size: (u32, u32),
    projector: Projector<'_>,
    (lo, hi): ([f64; 3], [f64; 3]),
    overlay: Overlay,
    name: &Path,
) -> Result<(), PictureError> {
    let mut lines = Vec::new();
    let mut labels = Vec::new();
    let corner =
        |k: usize| -> [f64; 3] { std::array::from_fn(|c| if k >> c & 1 == 0 { lo[c] } else { hi[c] }) };
    if overlay.outline {
        // Edges join corners that differ in one axis; a flat box's repeated edges are harmless.
        for a in 0..8usize {
            for axis in 0..3 {
                let b = a | 1 << axis;
                if b != a {
                    if let (Some(p), Some(q)) =
                        (projector.project(corner(a), size), projector.project(corner(b), size))
                    {
                        lines.push((p, q, [150, 150, 150]));
                    }
                }
            }
        }
    }
    if overlay.axes {
        let centre: [f64; 3] = std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]));
        let extent = (0..3).map(|c| hi[c] - lo[c]).fold(0.0f64, f64::max).max(1e-12);
        let origin = (44.0, f64::from(size.1) - 44.0);
        for (axis, (label, colour)) in
            [("x", [220, 40, 40]), ("y", [40, 170, 40]), ("z", [50, 90, 230])].into_iter().enumerate()
        {
            let mut tip = centre;
            tip[axis] += 0.1 * extent;
            let (Some(a), Some(b)) = (projector.project(centre, size), projector.project(tip, size)) else {
                continue;
            };
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let len = (dx * dx + dy * dy).sqrt();
            if len < 1e-9 * extent.max(1.0) || (matches!(projector, Projector::Plane { .. }) && axis == 2) {
                continue;
            }
            let (ux, uy) = (dx / len, dy / len);
            let end = (origin.0 + 30.0 * ux, origin.1 + 30.0 * uy);
            lines.push((origin, end, colour));
            labels.push(((end.0 + 8.0 * ux - 5.0, end.1 + 8.0 * uy - 9.0), label.to_string(), colour));
        }
    }
    crate::plot::draw_over_picture(rgba, size, &lines, &labels, name)?;
    Ok(())
}
