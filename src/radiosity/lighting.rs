//! Direct lighting, both ways of seed 000 §9:
//!
//! - **Area lights inside the model** ([`LightMode::Area`]): the window and skylight faces
//!   emit `e = window_exitance`; everything else has `e = 0`. The emission enters Eq. 14 and
//!   so the reduced model.
//! - **A sky outside the model** ([`LightMode::Sky`]): an overcast sky (CIE standard overcast,
//!   `L(θ) = L_z (1 + 2 cos θ)/3` for directions above the horizon; below it the ground,
//!   a Lambertian reflector of the sky's horizontal illuminance `E_h = 7π L_z / 9`, so
//!   `L = ρ_ground · 7 L_z / 9`) seen through the openings. A face's direct irradiance is
//!   `Eᵢ = Σ_{j opening} F_ij · π L(d_ij)`, each opening face acting as a Lambertian emitter of
//!   the sky radiance in the direction `d_ij` from `cᵢ` through it, and `eᵢ = ρᵢ Eᵢ`: computed
//!   at run time from the form factors to the openings, outside the reduced chain.
//!
//! Opening faces have albedo 0: light that leaves the rooms through them is lost.

use std::f64::consts::PI;

use super::form_factor::FormFactors;
use super::mesh::{FaceGeometry, SceneMesh};
use super::scene::{LightMode, Lights};
use super::solve::Rgb;

/// Radiance of the CIE overcast sky (and the ground below the horizon) in unit direction `d`
/// (pointing from the scene towards the sky).
pub fn sky_radiance(lights: &Lights, d: glam::DVec3) -> Rgb {
    let z = lights.sky_zenith;
    if d.z >= 0.0 {
        z.map(|l| l * (1.0 + 2.0 * d.z) / 3.0)
    } else {
        z.map(|l| lights.ground_albedo * 7.0 * l / 9.0)
    }
}

/// The emission `e` of every face: the openings' exitance in area mode, `ρᵢ Eᵢ` from the sky
/// in sky mode (which needs the form factors `f` to the openings).
pub fn emission(mesh: &SceneMesh, geometry: &FaceGeometry, lights: &Lights, f: &FormFactors) -> Vec<Rgb> {
    match lights.mode {
        LightMode::Area => {
            mesh.kind.iter().map(|k| if k.is_opening() { lights.window_exitance } else { [0.0; 3] }).collect()
        }
        LightMode::Sky => {
            let openings: Vec<usize> = (0..mesh.len()).filter(|&j| mesh.kind[j].is_opening()).collect();
            (0..mesh.len())
                .map(|i| {
                    if mesh.kind[i].is_opening() {
                        return [0.0; 3];
                    }
                    let mut irradiance = [0.0; 3];
                    for &j in &openings {
                        let fij = f.get(i, j);
                        if fij > 0.0 {
                            let d = (geometry.centroids[j] - geometry.centroids[i]).normalize();
                            let l = sky_radiance(lights, d);
                            for c in 0..3 {
                                irradiance[c] += fij * PI * l[c];
                            }
                        }
                    }
                    [0, 1, 2].map(|c| mesh.albedo[i][c] * irradiance[c])
                })
                .collect()
        }
    }
}
