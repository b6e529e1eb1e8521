//! Pixels of a surface render (surfaces in 3D, height fields) against the f64 surface.

use galerkin::spectral::SpectralMesh;

/// Of a surface's data render: the pixels covered, how far (px) the farthest one's point
/// `surface(e, r)` projects from its centre, and the worst value error as a fraction of its
/// pixel's f32 bound.
pub fn surface_errors(
    mesh: &SpectralMesh,
    pixels: &[f32],
    camera: &galerkin::render::Camera,
    size: (u32, u32),
    surface: impl Fn(usize, [f64; 2]) -> glam::DVec3,
) -> (usize, f64, f64) {
    let (mut covered, mut farthest, mut worst_value) = (0, 0.0f64, 0.0f64);
    for py in 0..size.1 {
        for px in 0..size.0 {
            let t = &pixels[4 * (py * size.0 + px) as usize..][..4];
            if t[3].is_nan() {
                continue;
            }
            covered += 1;
            let (e, r) = (t[3] as usize, [f64::from(t[1]), f64::from(t[2])]);
            let (sx, sy) = camera.project(surface(e, r), size.0, size.1);
            farthest = farthest.max((sx - (f64::from(px) + 0.5)).hypot(sy - (f64::from(py) + 0.5)));
            let bound = galerkin::spectral::reference::rounding_bound(mesh, 0, 0, e, r);
            worst_value = worst_value.max((f64::from(t[0]) - mesh.value(0, 0, e, r[0], r[1])).abs() / bound);
        }
    }
    (covered, farthest, worst_value)
}
