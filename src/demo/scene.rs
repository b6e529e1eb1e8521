//! The demo scene file (TOML, e.g. `scenes/demo.toml`): image size, camera, the field's
//! polynomial and tessellation, the colour map, and the axpy size. Errors name the file and
//! the line.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::field::Ramp;
use super::polynomial::BivariateCubic;
use crate::render::Camera;

/// Largest axpy the demo accepts: 2 arrays of 2 GiB on the host and on the device.
pub const MAX_AXPY_LEN: u64 = 1 << 29;

/// A bad scene file.
pub use crate::scene_file::SceneFileError as SceneError;

/// Output image size.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSize {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

/// The field pass's inputs.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FieldSpec {
    /// The cubic.
    pub coefficients: BivariateCubic,
    /// Squares per side of the tessellated square.
    #[serde(default = "default_tessellation")]
    pub tessellation: u32,
}

fn default_tessellation() -> u32 {
    8
}

/// Colour map choice.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColormapSpec {
    /// `viridis`, `cool-warm`, `grey`, or a ramp PNG's path (relative to the scene file).
    pub name: String,
    /// Value range mapped onto the map.
    pub range: [f64; 2],
    /// Logarithmic mapping.
    #[serde(default)]
    pub log: bool,
}

/// The compute pass's inputs.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxpySpec {
    /// Number of floats.
    pub n: u64,
    /// The scalar a.
    pub a: f64,
}

/// A whole demo scene.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DemoScene {
    /// Output size.
    pub image: ImageSize,
    /// The camera.
    pub camera: Camera,
    /// The field.
    pub field: FieldSpec,
    /// The colour map.
    pub colormap: ColormapSpec,
    /// The compute pass.
    pub axpy: AxpySpec,
    /// Directory of the scene file (ramp paths are relative to it).
    #[serde(skip)]
    pub dir: PathBuf,
}

impl DemoScene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        Self::parse(&crate::scene_file::read(path)?, path)
    }

    /// Parses and validates scene text; `path` names it in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SceneError> {
        let mut scene: DemoScene = crate::scene_file::parse(text, path)?;
        scene.dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let fail = |key: &str, message: String| Err(crate::scene_file::error_at(text, path, key, message));
        let ImageSize { width, height } = scene.image;
        if !(1..=16384).contains(&width) || !(1..=16384).contains(&height) {
            return fail("width", format!("image size {width}x{height} must be 1 to 16384 on each axis"));
        }
        if !(1..=512).contains(&scene.field.tessellation) {
            return fail(
                "tessellation",
                format!("tessellation {} must be 1 to 512", scene.field.tessellation),
            );
        }
        if let Some(i) = scene.field.coefficients.coefficients.iter().position(|c| !c.is_finite()) {
            return fail("coefficients", format!("coefficient {i} is not a finite number"));
        }
        let [lo, hi] = scene.colormap.range;
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return fail("range", format!("colour range [{lo}, {hi}] must be finite with lo < hi"));
        }
        if scene.colormap.log && lo <= 0.0 {
            return fail("range", format!("a logarithmic colour range needs lo > 0, got {lo}"));
        }
        if let Err(e) = scene.camera.check() {
            return fail("[camera]", e);
        }
        if !(1..=MAX_AXPY_LEN).contains(&scene.axpy.n) || !scene.axpy.a.is_finite() {
            return fail("[axpy]", format!("axpy needs 1 <= n <= {MAX_AXPY_LEN} and a finite a"));
        }
        Ok(scene)
    }

    /// The ramp settings.
    pub fn ramp(&self) -> Ramp {
        Ramp { lo: self.colormap.range[0], hi: self.colormap.range[1], log: self.colormap.log }
    }

    /// The colour map name or ramp path, ramp paths resolved against the scene's directory.
    pub fn colormap_name(&self) -> String {
        let n = &self.colormap.name;
        if n.to_ascii_lowercase().ends_with(".png") && Path::new(n).is_relative() {
            self.dir.join(n).display().to_string()
        } else {
            n.clone()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = include_str!("../../scenes/demo.toml");

    #[test]
    fn the_shipped_scene_parses() {
        let s = DemoScene::parse(GOOD, Path::new("scenes/demo.toml")).expect("demo scene parses");
        assert_eq!(s.image.width, 640);
        assert_eq!(s.axpy.n, 10_000_000);
    }

    #[test]
    fn errors_name_file_and_line() {
        let bad = GOOD.replace("tessellation = 8", "tessellation = \"eight\"");
        let e = DemoScene::parse(&bad, Path::new("x.toml")).unwrap_err();
        let line = GOOD.lines().position(|l| l.starts_with("tessellation")).unwrap() + 1;
        assert_eq!(e.line, line, "{e}");
        assert!(e.to_string().starts_with(&format!("x.toml:{line}:")), "{e}");

        let bad = GOOD.replace("range = [-2.5, 2.5]", "range = [2.5, -2.5]");
        let e = DemoScene::parse(&bad, Path::new("x.toml")).unwrap_err();
        assert!(e.message.contains("lo < hi"), "{e}");
        assert_eq!(e.line, GOOD.lines().position(|l| l.starts_with("range")).unwrap() + 1);

        let bad = GOOD.replace("[axpy]", "[axpy]\nbogus = 1");
        assert!(DemoScene::parse(&bad, Path::new("x.toml")).unwrap_err().message.contains("bogus"));
    }
}
