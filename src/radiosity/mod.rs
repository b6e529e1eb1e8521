//! Radiosity on deforming scenes (seed 000 §8–9).
//!
//! A scene ([`SceneSpec`], TOML) is generated as one triangle mesh of fixed topology whose
//! vertex positions `g` depend on the design parameters ([`architecture::build`]). The full
//! radiosity — the ground truth and the training data of the reduced model — samples the form
//! factors at face centroids (Eq. 15, [`form_factor`]) with visibility by segment casting
//! against a BVH ([`bvh`]), lights the scene by area lights in the openings or by a sky seen
//! through them ([`lighting`]) and solves Eq. 14 per colour channel ([`solve`]). Solutions are
//! drawn by a graphics pipeline ([`render`]). The same radiosity as Table 2's chain of
//! tensor operations, for the reduction core, is [`chain`].

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/radiosity/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_radiosity.rs"));
}
pub mod any_scene;
pub mod architecture;
pub use crate::mesh::bvh;
pub mod chain;
pub mod compare;
mod error;
pub mod estimate;
pub mod face_table;
pub mod form_factor;
pub mod full_frames;
pub mod gpu;
pub mod greedy;
pub mod lighting;
pub mod mesh;
pub mod near_correction;
pub mod near_field;
pub mod obj;
pub mod operator_correction;
pub mod picture;
pub mod reduced;
pub mod render;
pub mod scene;
pub mod snapshots;
pub mod solve;
pub mod train;
pub mod train_ranks;
pub mod train_stages;
#[cfg(feature = "viewer")]
pub mod viewer;
pub mod visibility;

pub use error::RadiosityError;
pub use form_factor::FormFactors;
pub use mesh::{FaceGeometry, FaceKind, SceneMesh};
pub use scene::{LightMode, Lights, Parameters, SceneSpec, PARAMETERS};
pub use solve::Rgb;

/// Relative change at which the Jacobi sweeps stop (f64: far below what a picture shows).
pub const JACOBI_TOLERANCE: f64 = 1e-10;
/// Sweeps allowed: `max ρ^k < 10⁻¹⁰` needs `k ≈ 23 / −ln(max ρ)`, about 130 for ρ = 0.85.
pub const JACOBI_MAX_SWEEPS: usize = 2000;

/// A full-space radiosity solution of one configuration.
#[derive(Clone, Debug)]
pub struct FullSolution {
    /// The mesh at the configuration.
    pub mesh: SceneMesh,
    /// Its face geometry.
    pub geometry: FaceGeometry,
    /// `F` (Eq. 15).
    pub form_factors: FormFactors,
    /// `e`.
    pub emission: Vec<Rgb>,
    /// `b` (Eq. 14).
    pub radiosity: Vec<Rgb>,
    /// Jacobi sweeps taken.
    pub sweeps: usize,
}

/// Full radiosity of the scene at parameters `p` on the CPU (f64).
pub fn full_radiosity(spec: &SceneSpec, p: &Parameters) -> Result<FullSolution, RadiosityError> {
    spec.check(p)?;
    let mesh = architecture::build(spec, p)?;
    full_radiosity_of(mesh, &spec.lights)
}

/// Full radiosity of a given mesh under `lights` (CPU, f64), the form factors by centroid
/// sampling with the default near field (what the reduced model's chain computes).
pub fn full_radiosity_of(mesh: SceneMesh, lights: &Lights) -> Result<FullSolution, RadiosityError> {
    full_radiosity_with(mesh, lights, near_field::FormFactorMethod::Centroid)
}

/// Full radiosity of a given mesh under `lights` (CPU, f64) with the form factors of `method`
/// ([`near_field::FormFactorMethod::ExactNear`]: exact polygon form factors for near pairs).
pub fn full_radiosity_with(
    mesh: SceneMesh,
    lights: &Lights,
    method: near_field::FormFactorMethod,
) -> Result<FullSolution, RadiosityError> {
    mesh.validate()?;
    let geometry = mesh.geometry();
    let form_factors = match method {
        near_field::FormFactorMethod::Centroid => {
            form_factor::form_factors(&mesh, form_factor::NearField::default())
        }
        near_field::FormFactorMethod::ExactNear { reach } => {
            near_field::form_factors_exact_near(&mesh, reach).0
        }
    };
    let emission = lighting::emission(&mesh, &geometry, lights, &form_factors);
    let (radiosity, sweeps) =
        solve::solve_jacobi(&form_factors, &mesh.albedo, &emission, JACOBI_TOLERANCE, JACOBI_MAX_SWEEPS)?;
    Ok(FullSolution { mesh, geometry, form_factors, emission, radiosity, sweeps })
}
