//! A perspective camera with Vulkan's conventions (framebuffer y down, depth in [0, 1]),
//! kept in f64 so that CPU references can cast exact rays through pixel centres; the GPU gets
//! the f32 matrix.

use glam::{DMat4, DVec3, DVec4, Mat4};
use serde::Deserialize;

/// A look-at perspective camera.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up direction.
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov_y_degrees: f64,
    /// Near plane distance.
    #[serde(default = "default_near")]
    pub near: f64,
    /// Far plane distance.
    #[serde(default = "default_far")]
    pub far: f64,
}

fn default_up() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}
fn default_fov() -> f64 {
    45.0
}
fn default_near() -> f64 {
    0.05
}
fn default_far() -> f64 {
    100.0
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            eye: [0.0, -2.5, 2.0],
            target: [0.0; 3],
            up: default_up(),
            fov_y_degrees: 45.0,
            near: 0.05,
            far: 100.0,
        }
    }
}

impl Camera {
    /// Refuses a camera that has no view: a coordinate that is not finite, the eye on its
    /// target, an up vector that is zero or along the line of sight (the view's right axis
    /// `f × up` would be NaN), a field of view outside (0°, 180°), or not `0 < near < far`.
    pub fn check(&self) -> Result<(), String> {
        let all = self.eye.iter().chain(&self.target).chain(&self.up);
        if all.chain([&self.fov_y_degrees, &self.near, &self.far]).any(|v| !v.is_finite()) {
            return Err(format!("camera {self:?}: every value must be finite"));
        }
        let f = DVec3::from(self.target) - DVec3::from(self.eye);
        let up = DVec3::from(self.up);
        if f.length() == 0.0 {
            return Err(format!("camera: eye and target are the same point {:?}", self.eye));
        }
        if up.length() == 0.0 {
            return Err("camera: the up vector is zero".into());
        }
        if f.normalize().cross(up.normalize()).length() < 1e-6 {
            return Err(format!(
                "camera: the up vector {:?} is along the line of sight (eye {:?} → target {:?}); give one across it",
                self.up, self.eye, self.target
            ));
        }
        if !(self.fov_y_degrees > 0.0 && self.fov_y_degrees < 180.0) {
            return Err(format!("camera: fov_y_degrees {} must be in (0, 180)", self.fov_y_degrees));
        }
        if !(self.near > 0.0 && self.near < self.far) {
            return Err(format!("camera: needs 0 < near < far, got near {} and far {}", self.near, self.far));
        }
        Ok(())
    }

    /// World → clip matrix in f64: right-handed view, perspective with depth in [0, 1], y
    /// flipped so that clip +y is framebuffer down (Vulkan).
    pub fn view_proj(&self, aspect: f64) -> DMat4 {
        self.projection(aspect) * self.view()
    }

    /// World → eye: right-handed, the eye looks down −z with `up` as +y.
    pub fn view(&self) -> DMat4 {
        let eye = DVec3::from(self.eye);
        let f = (DVec3::from(self.target) - eye).normalize();
        let s = f.cross(DVec3::from(self.up)).normalize();
        let u = s.cross(f);
        DMat4::from_cols(
            DVec4::new(s.x, u.x, -f.x, 0.0),
            DVec4::new(s.y, u.y, -f.y, 0.0),
            DVec4::new(s.z, u.z, -f.z, 0.0),
            DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        )
    }

    /// Eye → clip for Vulkan: depth 0 at `near` and 1 at `far`, clip +y down the framebuffer.
    pub fn projection(&self, aspect: f64) -> DMat4 {
        let g = 1.0 / (0.5 * self.fov_y_degrees.to_radians()).tan();
        let (n, f) = (self.near, self.far);
        DMat4::from_cols(
            DVec4::new(g / aspect, 0.0, 0.0, 0.0),
            DVec4::new(0.0, -g, 0.0, 0.0),
            DVec4::new(0.0, 0.0, f / (n - f), -1.0),
            DVec4::new(0.0, 0.0, n * f / (n - f), 0.0),
        )
    }

    /// Pixels per world unit at view depth 1 in a picture `height` pixels tall:
    /// height / (2 tan(fov/2)) (a length ℓ at view depth z spans ℓ · this / z pixels).
    pub fn pixels_per_unit(&self, height: u32) -> f64 {
        0.5 * f64::from(height) / (0.5 * self.fov_y_degrees.to_radians()).tan()
    }

    /// The f32 matrix for shaders.
    pub fn view_proj_f32(&self, aspect: f64) -> Mat4 {
        self.view_proj(aspect).as_mat4()
    }

    /// The world-space ray (origin on the near plane, unit direction) through the centre of
    /// pixel (`px`, `py`) of a `width`×`height` image, pixel (0, 0) at the top left.
    pub fn pixel_ray(&self, px: u32, py: u32, width: u32, height: u32) -> (DVec3, DVec3) {
        self.ray_through(f64::from(px) + 0.5, f64::from(py) + 0.5, width, height)
    }

    /// The world-space ray through the continuous pixel position (`x`, `y`) (pixel centres at
    /// +0.5) of a `width`×`height` image.
    pub fn ray_through(&self, x: f64, y: f64, width: u32, height: u32) -> (DVec3, DVec3) {
        let inv = self.view_proj(f64::from(width) / f64::from(height)).inverse();
        let x = 2.0 * x / f64::from(width) - 1.0;
        let y = 2.0 * y / f64::from(height) - 1.0;
        let near = inv * DVec4::new(x, y, 0.0, 1.0);
        let far = inv * DVec4::new(x, y, 1.0, 1.0);
        let (a, b) = (near.truncate() / near.w, far.truncate() / far.w);
        (a, (b - a).normalize())
    }

    /// Where the ray through pixel (`px`, `py`) meets the plane z = `z0`, if it does in front.
    pub fn pixel_on_plane_z(&self, px: u32, py: u32, width: u32, height: u32, z0: f64) -> Option<DVec3> {
        let (o, d) = self.pixel_ray(px, py, width, height);
        if d.z.abs() < 1e-300 {
            return None;
        }
        let s = (z0 - o.z) / d.z;
        (s > 0.0).then(|| o + s * d)
    }

    /// Pixel coordinates (continuous, pixel centres at +0.5) of a world point.
    pub fn project(&self, p: DVec3, width: u32, height: u32) -> (f64, f64) {
        let c = self.view_proj(f64::from(width) / f64::from(height)) * p.extend(1.0);
        let (x, y) = (c.x / c.w, c.y / c.w);
        ((x + 1.0) * 0.5 * f64::from(width), (y + 1.0) * 0.5 * f64::from(height))
    }
}

/// Where a camera looks at a box from (`--camera AZ,EL[,DIST]`): the azimuth in degrees from +x
/// towards +y, the elevation in degrees above the x–y plane (z up), and the distance as a
/// multiple of the distance at which the box's bounding sphere fills the view (1: fitted).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Degrees from +x towards +y.
    pub azimuth: f64,
    /// Degrees above the x–y plane, within ±89 (at ±90 the up vector would be the line of sight).
    pub elevation: f64,
    /// Multiple of the fitted distance, (0, 100].
    pub distance: f64,
    /// `Some(width / height)` (`--fit`): the fitted distance is the closest at which the box's
    /// eight corners all lie inside a picture of this aspect; `None`: the distance at which the
    /// box's bounding sphere fills the view (looser, the same from every direction).
    pub tight_aspect: Option<f64>,
}

/// The direction the default cameras look from ([`camera_for_box`]): above the x–y diagonal.
const DEFAULT_DIRECTION: [f64; 3] = [0.45, -0.75, 0.55];

impl Orbit {
    /// Parses `AZ,EL` or `AZ,EL,DIST` (degrees, degrees, multiple of the fitted distance; DIST
    /// defaults to 1); the message names what is out of range.
    pub fn parse(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if !(2..=3).contains(&parts.len()) {
            return Err(format!("{s:?} is not AZ,EL or AZ,EL,DIST"));
        }
        let num = |v: &str, what: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("{what} {v:?} is not a number"))
        };
        let azimuth = num(parts[0], "azimuth")?;
        let elevation = num(parts[1], "elevation")?;
        if elevation.abs() > 89.0 {
            return Err(format!("elevation {elevation}: give −89 to 89 degrees (z is up)"));
        }
        let distance = match parts.get(2) {
            Some(d) => num(d, "distance")?,
            None => 1.0,
        };
        if !(distance > 0.0 && distance <= 100.0) {
            return Err(format!(
                "distance {distance}: a multiple of the fitted distance above 0, at most 100"
            ));
        }
        Ok(Self { azimuth, elevation, distance, tight_aspect: None })
    }

    /// The default cameras' direction ([`camera_for_box`]) as an orbit at the fitted distance:
    /// what `--fit` alone starts from.
    pub fn default_view() -> Self {
        let [x, y, z] = DEFAULT_DIRECTION;
        let n = (x * x + y * y + z * z).sqrt();
        Self {
            azimuth: y.atan2(x).to_degrees(),
            elevation: (z / n).asin().to_degrees(),
            distance: 1.0,
            tight_aspect: None,
        }
    }

    /// The camera looking at the centre of the box [`lo`, `hi`] from this direction, at this
    /// multiple of the distance at which the box's bounding sphere fills a 40° view.
    /// With [`Orbit::tight_aspect`], the distance is instead the closest at which every corner
    /// of the box projects inside the picture (2 % margin), times `distance`.
    pub fn camera(&self, lo: [f64; 3], hi: [f64; 3]) -> Camera {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        let dir = [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()];
        let mut camera = camera_along(lo, hi, dir, self.distance);
        if let Some(aspect) = self.tight_aspect.filter(|a| a.is_finite() && *a > 0.0) {
            let d = self.distance * tight_distance(lo, hi, dir, camera.fov_y_degrees, aspect);
            let centre: [f64; 3] = std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]));
            let radius = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt().max(1e-12) * 0.5;
            camera.eye = std::array::from_fn(|c| centre[c] + d * dir[c]);
            camera.near = (d - 1.5 * radius).max(1e-3 * d);
            camera.far = d + 1.5 * radius;
        }
        camera
    }
}

/// The least distance from the box's centre along the unit vector `dir` at which a camera
/// looking at the centre (z up, vertical field of view `fov_y` degrees, `aspect` = width /
/// height) sees all eight corners of the box, with a 2 % margin: for a corner at offset `c`
/// from the centre, its depth is `d − c·dir` and it must satisfy |c·right| ≤ tan(½fov_x)·depth
/// and |c·up| ≤ tan(½fov_y)·depth.
fn tight_distance(lo: [f64; 3], hi: [f64; 3], dir: [f64; 3], fov_y: f64, aspect: f64) -> f64 {
    let v = |a: [f64; 3]| glam::DVec3::from_array(a);
    let forward = -v(dir).normalize();
    let right = forward.cross(glam::DVec3::Z).normalize_or(glam::DVec3::X);
    let up = right.cross(forward);
    let tan_y = (0.5 * fov_y.to_radians()).tan() / 1.02;
    let tan_x = tan_y * aspect;
    let centre = 0.5 * (v(lo) + v(hi));
    let mut d: f64 = 1e-12;
    for k in 0..8 {
        let corner = glam::DVec3::new(
            if k & 1 == 0 { lo[0] } else { hi[0] },
            if k & 2 == 0 { lo[1] } else { hi[1] },
            if k & 4 == 0 { lo[2] } else { hi[2] },
        );
        let c = corner - centre;
        let toward_eye = -c.dot(forward);
        d = d.max(toward_eye + c.dot(right).abs() / tan_x).max(toward_eye + c.dot(up).abs() / tan_y);
    }
    d
}

/// A camera that shows the box [`lo`, `hi`] (its bounding sphere) from above the x–y diagonal.
pub fn camera_for_box(lo: [f64; 3], hi: [f64; 3]) -> Camera {
    camera_along(lo, hi, DEFAULT_DIRECTION, 1.0)
}

/// A camera on the line through the box's centre along `dir`, at `scale` times the distance at
/// which the box's bounding sphere fills a 40° view.
fn camera_along(lo: [f64; 3], hi: [f64; 3], dir: [f64; 3], scale: f64) -> Camera {
    let centre: [f64; 3] = std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]));
    let radius = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt().max(1e-12) * 0.5;
    let fov: f64 = 40.0;
    let distance = scale * 1.05 * radius / (0.5 * fov.to_radians()).sin();
    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
    Camera {
        eye: std::array::from_fn(|c| centre[c] + distance * dir[c] / n),
        target: centre,
        up: [0.0, 0.0, 1.0],
        fov_y_degrees: fov,
        near: (distance - 1.5 * radius).max(1e-3 * distance),
        far: distance + 1.5 * radius,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_parses_its_angles_and_places_the_eye_along_them() {
        let o = Orbit::parse("0, 0").expect("AZ,EL");
        assert_eq!(o, Orbit { azimuth: 0.0, elevation: 0.0, distance: 1.0, tight_aspect: None });
        let (lo, hi) = ([-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]);
        let c = o.camera(lo, hi);
        // On +x, level with the centre, looking at it, z up.
        assert!(c.eye[0] > 1.0 && c.eye[1].abs() < 1e-12 && c.eye[2].abs() < 1e-12, "{:?}", c.eye);
        assert_eq!(c.target, [0.0; 3]);
        assert!(c.check().is_ok());
        // From above at 60°, twice as far.
        let far = Orbit::parse("90,60,2").expect("AZ,EL,DIST").camera(lo, hi);
        let d = |c: &Camera| c.eye.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!((d(&far) - 2.0 * d(&c)).abs() < 1e-12);
        assert!((far.eye[2] / d(&far) - 60f64.to_radians().sin()).abs() < 1e-12);
        assert!(far.eye[0].abs() < 1e-12 && far.eye[1] > 0.0);
        for bad in ["10", "1,2,3,4", "x,1", "0,90", "0,0,0", "0,0,-1", "nan,0"] {
            assert!(Orbit::parse(bad).is_err(), "{bad} accepted");
        }
    }

    /// `--fit`: every corner of the box projects inside the picture, and at least one touches
    /// its margin (the fit is tight), for boxes of several shapes, directions and aspects; the
    /// default view's direction is the default camera's.
    #[test]
    fn a_tight_fit_keeps_every_corner_inside_and_touches_an_edge() {
        let default = camera_for_box([-1.0; 3], [1.0; 3]);
        let again = Orbit::default_view().camera([-1.0; 3], [1.0; 3]);
        for c in 0..3 {
            assert!((default.eye[c] - again.eye[c]).abs() < 1e-9, "{:?} {:?}", default.eye, again.eye);
        }
        for (lo, hi) in [
            ([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
            ([-3.0, 0.0, 0.0], [3.0, 0.5, 0.2]),
            ([0.0; 3], [0.1, 2.0, 0.0]),
        ] {
            for (az, el) in [(0.0, 0.0), (-59.0, 32.0), (135.0, 70.0), (90.0, -30.0)] {
                for (w, h) in [(1280u32, 720u32), (400, 800)] {
                    let orbit = Orbit {
                        azimuth: az,
                        elevation: el,
                        distance: 1.0,
                        tight_aspect: Some(f64::from(w) / f64::from(h)),
                    };
                    let camera = orbit.camera(lo, hi);
                    assert!(camera.check().is_ok());
                    let mut touches = false;
                    for k in 0..8 {
                        let p = glam::DVec3::new(
                            if k & 1 == 0 { lo[0] } else { hi[0] },
                            if k & 2 == 0 { lo[1] } else { hi[1] },
                            if k & 4 == 0 { lo[2] } else { hi[2] },
                        );
                        let (x, y) = camera.project(p, w, h);
                        let (fx, fy) = (x / f64::from(w), y / f64::from(h));
                        assert!(
                            (0.0..=1.0).contains(&fx) && (0.0..=1.0).contains(&fy),
                            "corner {p} at ({fx}, {fy})"
                        );
                        touches |= !(0.015..=0.985).contains(&fx) || !(0.015..=0.985).contains(&fy);
                    }
                    assert!(
                        touches,
                        "box {lo:?}..{hi:?} from ({az}, {el}) at {w}x{h}: no corner near an edge"
                    );
                }
            }
        }
    }
}
