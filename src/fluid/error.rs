//! Errors of the fluid module: each names the scene key, file, frame, cell or face at fault.

use std::path::PathBuf;

/// What can go wrong setting up or running a fluid simulation.
#[derive(Debug, thiserror::Error)]
pub enum FluidError {
    /// A bad mesh (inverted cell, non-manifold face, unmatched periodic vertex, NaN).
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A scene file that does not parse or validate (names the file and line).
    #[error(transparent)]
    Scene(#[from] crate::scene_file::SceneFileError),
    /// A state or parameter that does not fit the mesh or is not finite.
    #[error("{0}")]
    State(String),
    /// The boundary moves with a net change of the fluid's volume: no incompressible flow
    /// satisfies the constraints.
    #[error("frame {frame}: the boundary changes the fluid volume by {net:e} ({relative:e} of the boundary flux): incompressible flow is impossible; renormalise the volume")]
    VolumeChange {
        /// The frame.
        frame: usize,
        /// Net outward boundary flux × frame time.
        net: f64,
        /// Relative to the total |boundary flux|.
        relative: f64,
    },
    /// The projection's linear system failed.
    #[error("pressure projection: {0}")]
    Projection(String),
    /// A plot that could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// A snapshot directory that cannot be written or read.
    #[error("{path}: {message}")]
    File {
        /// The file or directory.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Writing a picture failed (the message names the file).
    #[error(transparent)]
    Picture(#[from] crate::picture::PictureError),
    /// The device failed (out of memory, device lost) or a request exceeds its limits.
    #[error("device: {0}")]
    Gpu(#[from] crate::gpu::GpuError),
    /// The reduction core failed (a basis, a tensor, a model file, the device under it).
    #[error(transparent)]
    Reduce(#[from] crate::reduce::ReduceError),
}

impl crate::gpu::GpuFailure for FluidError {
    fn gpu_error(&self) -> Option<&crate::gpu::GpuError> {
        match self {
            Self::Gpu(e) => Some(e),
            Self::Reduce(e) => e.gpu_error(),
            _ => None,
        }
    }
}

impl FluidError {
    /// Wraps an I/O failure on `path` (for `map_err`).
    pub fn io(path: &std::path::Path) -> impl Fn(std::io::Error) -> Self + '_ {
        move |e| Self::File { path: path.to_path_buf(), message: e.to_string() }
    }
}
