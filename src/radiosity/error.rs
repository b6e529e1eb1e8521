//! Errors of the radiosity module: a bad scene names the file and line or the parameter, a bad
//! mesh names the face or vertex.

use std::path::PathBuf;

/// What can go wrong with a radiosity scene or its solution.
#[derive(Debug, thiserror::Error)]
pub enum RadiosityError {
    /// A scene file that does not parse or does not validate (names the file and line).
    #[error(transparent)]
    Scene(#[from] crate::scene_file::SceneFileError),
    /// A parameter value outside its declared range, or an unknown parameter.
    #[error("parameter {name}: {message}")]
    Parameter {
        /// The parameter.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A face with (numerically) zero area.
    #[error("face {face} ({part}): degenerate triangle (area {area:e} m²)")]
    DegenerateFace {
        /// The face.
        face: usize,
        /// The scene part it belongs to.
        part: String,
        /// Its area.
        area: f64,
    },
    /// A NaN or infinity in a vertex, albedo or light.
    #[error("{what} is not finite")]
    NotFinite {
        /// Which value (names the vertex or face).
        what: String,
    },
    /// A mesh whose arrays disagree (a face referencing a missing vertex, wrong lengths).
    #[error("{0}")]
    Mesh(String),
    /// A file that cannot be used: an OBJ file, a saved reduced model.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The linear solve failed (a singular `I − ρF`: albedo ≥ 1 in a closed scene).
    #[error("radiosity solve: {0}")]
    Solve(String),
    /// A reduced model's answer that is not to be trusted at these parameters
    /// ([`super::estimate::Estimate::untrusted`]: its reduced operator's margin, or its error
    /// estimate above the threshold).
    #[error("the reduced radiosity is not to be trusted here: {0}")]
    Untrusted(String),
    /// Writing a picture failed (the message names the file).
    #[error(transparent)]
    Picture(#[from] crate::picture::PictureError),
    /// A device error.
    #[error(transparent)]
    Gpu(#[from] crate::gpu::GpuError),
    /// The reduction core failed while training or loading a model (a basis, a tensor, the
    /// device under it).
    #[error("reduced model: {0}")]
    Reduce(#[from] crate::reduce::ReduceError),
}

impl crate::gpu::GpuFailure for RadiosityError {
    fn gpu_error(&self) -> Option<&crate::gpu::GpuError> {
        match self {
            Self::Gpu(e) => Some(e),
            Self::Reduce(e) => e.gpu_error(),
            _ => None,
        }
    }
}
