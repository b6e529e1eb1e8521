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

/// A camera that shows the box [`lo`, `hi`] (its bounding sphere) from above the x–y diagonal.
pub fn camera_for_box(lo: [f64; 3], hi: [f64; 3]) -> Camera {
    let centre: [f64; 3] = std::array::from_fn(|c| 0.5 * (lo[c] + hi[c]));
    let radius = (0..3).map(|c| (hi[c] - lo[c]).powi(2)).sum::<f64>().sqrt().max(1e-12) * 0.5;
    let fov: f64 = 40.0;
    let distance = 1.05 * radius / (0.5 * fov.to_radians()).sin();
    let dir: [f64; 3] = [0.45, -0.75, 0.55];
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
