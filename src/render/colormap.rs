//! Colour maps as 1D textures: viridis, Moreland's cool-warm, grey, or a user-supplied ramp
//! image. A value becomes a colour in two steps, each written once in GLSL
//! (`shaders-glsl/include/colormap.glsl`) and once here, and tested to agree:
//! [`ramp_coordinate`] (linear or logarithmic over a range, clamped to [0, 1]) and
//! [`ramp_texcoord`] (so that t = 0 and t = 1 land on the first and last texel centres), then
//! the sampler's linear filtering between texels, mirrored by [`Colormap::sample`].

use std::path::Path;

use ash::vk;

use super::colormap_data::{COOL_WARM, VIRIDIS};
use super::error::RenderError;
use super::image_io::read_png_rgba8;
use crate::gpu::{Gpu, GpuResult, Image, ImageDesc, Resource, Sampler};

/// Texels of the built-in ramps.
pub const RAMP_TEXELS: usize = 256;

/// A colour map: a ramp of 8-bit sRGB texels.
#[derive(Clone, Debug, PartialEq)]
pub struct Colormap {
    name: String,
    texels: Vec<[u8; 4]>,
}

fn quantise(c: [f64; 3]) -> [u8; 4] {
    let q = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [q(c[0]), q(c[1]), q(c[2]), 255]
}

impl Colormap {
    /// Viridis (matplotlib's 256 entries).
    pub fn viridis() -> Self {
        let texels = VIRIDIS.iter().map(|c| quantise([c[0].into(), c[1].into(), c[2].into()])).collect();
        Self { name: "viridis".into(), texels }
    }

    /// Moreland's cool-warm diverging map: its 33 control points linearly interpolated to 256.
    pub fn cool_warm() -> Self {
        let n = COOL_WARM.len() - 1;
        let texels = (0..RAMP_TEXELS)
            .map(|k| {
                let x = k as f64 / (RAMP_TEXELS - 1) as f64 * n as f64;
                let i = (x.floor() as usize).min(n - 1);
                let f = x - i as f64;
                let c = |ch: usize| COOL_WARM[i][ch] * (1.0 - f) + COOL_WARM[i + 1][ch] * f;
                quantise([c(0), c(1), c(2)])
            })
            .collect();
        Self { name: "cool-warm".into(), texels }
    }

    /// Black to white.
    pub fn grey() -> Self {
        let texels = (0..RAMP_TEXELS)
            .map(|k| {
                let v = k as f64 / (RAMP_TEXELS - 1) as f64;
                quantise([v, v, v])
            })
            .collect();
        Self { name: "grey".into(), texels }
    }

    /// The grey levels the radiosity tone map gives radiances 0 to `max_radiance` at
    /// `exposure` ([`super::tone_map`]): the colour bar of a tone-mapped picture, read as a
    /// radiance scale (a neutral radiance L shows as the texel at L / `max_radiance`).
    pub fn tone_ramp(exposure: f64, max_radiance: f64) -> Self {
        let texels = (0..RAMP_TEXELS)
            .map(|k| {
                let radiance = max_radiance * k as f64 / (RAMP_TEXELS - 1) as f64;
                quantise(super::tone_map([radiance; 3], exposure))
            })
            .collect();
        Self { name: "tone map".into(), texels }
    }

    /// A ramp read from an image: its middle row, left (t = 0) to right (t = 1), at least 2
    /// pixels wide and at most `maxImageDimension1D` (4096 is safe everywhere).
    pub fn from_ramp_image(path: &Path) -> Result<Self, RenderError> {
        let (w, h, rgba) = read_png_rgba8(path)?;
        if !(2..=4096).contains(&w) {
            return Err(RenderError::Colormap {
                name: path.display().to_string(),
                detail: format!("a ramp image must be 2 to 4096 pixels wide, this one is {w}"),
            });
        }
        let row = (h / 2) as usize * w as usize * 4;
        let texels =
            rgba[row..row + 4 * w as usize].chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]).collect();
        Ok(Self { name: path.display().to_string(), texels })
    }

    /// A ramp through colour points (x, [r, g, b] in [0, 1]) — ParaView's `RGBPoints` — with x
    /// strictly increasing: its first and last x span the ramp, colours linear between points,
    /// sampled to [`RAMP_TEXELS`] texels.
    pub fn from_points(name: &str, points: &[(f64, [f64; 3])]) -> Result<Self, String> {
        if points.len() < 2 {
            return Err(format!("{} colour points; a ramp needs at least 2", points.len()));
        }
        for (k, w) in points.windows(2).enumerate() {
            if !(w[0].0.is_finite() && w[1].0.is_finite()) || w[1].0 <= w[0].0 {
                return Err(format!(
                    "colour point {}'s x {} does not follow {} (x must increase)",
                    k + 1,
                    w[1].0,
                    w[0].0
                ));
            }
        }
        if let Some(k) = points.iter().position(|p| p.1.iter().any(|c| !(0.0..=1.0).contains(c))) {
            return Err(format!("colour point {k}: {:?} is not in [0, 1]", points[k].1));
        }
        let (x0, x1) = (points[0].0, points[points.len() - 1].0);
        let texels = (0..RAMP_TEXELS)
            .map(|k| {
                let x = x0 + (x1 - x0) * k as f64 / (RAMP_TEXELS - 1) as f64;
                let i = points.windows(2).position(|w| x <= w[1].0).unwrap_or(points.len() - 2);
                let (a, b) = (points[i], points[i + 1]);
                let f = ((x - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
                quantise(std::array::from_fn(|c| a.1[c] * (1.0 - f) + b.1[c] * f))
            })
            .collect();
        Ok(Self { name: name.to_string(), texels })
    }

    /// By name (`viridis`, `cool-warm`, `grey`) or, failing that, as the path of a ramp PNG.
    pub fn by_name(name: &str) -> Result<Self, RenderError> {
        match name.to_ascii_lowercase().as_str() {
            "viridis" => Ok(Self::viridis()),
            "cool-warm" | "coolwarm" => Ok(Self::cool_warm()),
            "grey" | "gray" => Ok(Self::grey()),
            _ if Path::new(name).extension().is_some_and(|e| e.eq_ignore_ascii_case("png")) => {
                Self::from_ramp_image(Path::new(name))
            }
            _ => Err(RenderError::Colormap {
                name: name.to_string(),
                detail: "not a built-in map (viridis, cool-warm, grey) nor a .png ramp image".into(),
            }),
        }
    }

    /// Its name (or the ramp image's path).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The texels, t = 0 first.
    pub fn texels(&self) -> &[[u8; 4]] {
        &self.texels
    }

    /// CPU f64 reference of what a linear, clamp-to-edge sampler returns at ramp coordinate
    /// `t` ∈ [0, 1] (through [`ramp_texcoord`]): RGBA in [0, 1].
    pub fn sample(&self, t: f64) -> [f64; 4] {
        let n = self.texels.len();
        let u = ramp_texcoord(t, n as f64);
        let x = (u * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let i = (x.floor() as usize).min(n - 2);
        let f = x - i as f64;
        let (a, b) = (self.texels[i], self.texels[i + 1]);
        std::array::from_fn(|c| (f64::from(a[c]) * (1.0 - f) + f64::from(b[c]) * f) / 255.0)
    }

    /// Uploads the ramp as a 1D RGBA8 texture with a linear sampler.
    pub fn upload(&self, gpu: &Gpu) -> GpuResult<ColormapTexture> {
        let mut image = Image::new(
            gpu,
            &format!("colormap {}", self.name),
            ImageDesc::texture_1d(self.texels.len() as u32, vk::Format::R8G8B8A8_UNORM),
        )?;
        image.upload(gpu, bytemuck::cast_slice(&self.texels))?;
        Ok(ColormapTexture { image, sampler: Sampler::new(gpu, true)?, texels: self.texels.len() as u32 })
    }
}

/// A colour map resident on the device.
pub struct ColormapTexture {
    image: Image,
    sampler: Sampler,
    texels: u32,
}

impl ColormapTexture {
    /// The texture binding for a descriptor set.
    pub fn resource(&self) -> Resource<'_> {
        Resource::Texture { image: &self.image, sampler: &self.sampler }
    }

    /// Number of texels (shaders need it for [`ramp_texcoord`]).
    pub fn texels(&self) -> u32 {
        self.texels
    }
}

/// Ramp coordinate of value `v` over `[lo, hi]`: linear, or logarithmic when `log` (for
/// positive ranges; values ≤ 0 map to 0), clamped to [0, 1]. Twin of `ramp_coordinate` in
/// `colormap.glsl`.
pub fn ramp_coordinate(v: f64, lo: f64, hi: f64, log: bool) -> f64 {
    let t = if log {
        if v <= 0.0 || lo <= 0.0 || hi <= lo {
            0.0
        } else {
            (v / lo).ln() / (hi / lo).ln()
        }
    } else if hi == lo {
        0.0
    } else {
        (v - lo) / (hi - lo)
    };
    if t.is_nan() {
        0.0
    } else {
        t.clamp(0.0, 1.0)
    }
}

/// Texture coordinate of ramp coordinate `t` on an `n`-texel ramp: t = 0 and t = 1 land on the
/// centres of the first and last texels. Twin of `ramp_texcoord` in `colormap.glsl`.
pub fn ramp_texcoord(t: f64, n: f64) -> f64 {
    (t * (n - 1.0) + 0.5) / n
}
