//! Errors of the render layer: files that cannot be read or written, bad ramp images, and
//! device errors underneath.

use std::path::PathBuf;

use crate::gpu::GpuError;

/// What can go wrong while rendering or writing images.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Reading or writing a file failed.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error (shown in the message, so not also the error's `source`).
        cause: std::io::Error,
    },
    /// An image file could not be encoded or decoded.
    #[error("{path}: {detail}")]
    Image {
        /// The file.
        path: PathBuf,
        /// What the codec said.
        detail: String,
    },
    /// A colour map name or ramp that cannot be used.
    #[error("colour map {name:?}: {detail}")]
    Colormap {
        /// The name or path given.
        name: String,
        /// Why it is unusable.
        detail: String,
    },
    /// The device failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

impl crate::gpu::GpuFailure for RenderError {
    fn gpu_error(&self) -> Option<&GpuError> {
        match self {
            Self::Gpu(e) => Some(e),
            _ => None,
        }
    }
}
