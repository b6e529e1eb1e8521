//! Phong illumination with diffuse and specular reflectances as multiples of the surface
//! colour (seed 003 §4.2.3). Twin of `shaders-glsl/include/phong.glsl`; the constants and the
//! formula are the same, and a test checks the two agree.

/// Ambient reflectance (times the colour).
pub const PHONG_AMBIENT: f64 = 0.3;
/// Diffuse reflectance (times the colour).
pub const PHONG_DIFFUSE: f64 = 0.7;
/// Specular reflectance (times the colour).
pub const PHONG_SPECULAR: f64 = 0.25;
/// Specular exponent.
pub const PHONG_SHININESS: f64 = 24.0;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Lit colour of `colour` at a point with unit normal `n`, unit direction to the light `l` and
/// unit direction to the eye `v`; two-sided (the normal is flipped to face the eye).
pub fn phong(colour: [f64; 3], n: [f64; 3], l: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    let n = if dot(n, v) < 0.0 { n.map(|x| -x) } else { n };
    let nl = dot(n, l);
    let diffuse = nl.max(0.0);
    let r = [2.0 * nl * n[0] - l[0], 2.0 * nl * n[1] - l[1], 2.0 * nl * n[2] - l[2]];
    let specular = if diffuse > 0.0 { dot(r, v).max(0.0).powf(PHONG_SHININESS) } else { 0.0 };
    colour.map(|c| c * (PHONG_AMBIENT + PHONG_DIFFUSE * diffuse + PHONG_SPECULAR * specular))
}
