//! Errors of the spectral module: bad data name the element, field or file.

use std::path::PathBuf;

/// What can go wrong with a spectral-element data set or its rendering.
#[derive(Debug, thiserror::Error)]
pub enum SpectralError {
    /// A polynomial order outside what the basis evaluation supports.
    #[error("{what}: order {order} is outside 1..={max}")]
    Order {
        /// Which basis (field or geometry).
        what: String,
        /// The order asked for.
        order: usize,
        /// The largest order supported.
        max: usize,
    },
    /// A NaN or infinity in a node position or a field value.
    #[error("element {element}: {what} is not finite")]
    NotFinite {
        /// The element.
        element: usize,
        /// Which value.
        what: String,
    },
    /// An element whose geometry map folds or collapses (non-positive Jacobian somewhere).
    #[error("element {element}: {what}")]
    Invalid {
        /// The element.
        element: usize,
        /// What is wrong.
        what: String,
    },
    /// Array lengths that disagree.
    #[error("{what}: {found} entries, expected {expected}")]
    Length {
        /// The array.
        what: String,
        /// Entries found.
        found: usize,
        /// Entries expected.
        expected: usize,
    },
    /// A field or time step that does not exist.
    #[error("{0}")]
    Missing(String),
    /// A view setting that cannot be drawn (a camera without a view).
    #[error("{0}")]
    View(String),
    /// A derived field (`--expr`) that does not parse, type-check, compile or suit the view.
    #[error("{0}")]
    Expression(String),
    /// A problem reading or writing a file.
    #[error("{path}: {detail}")]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        detail: String,
    },
    /// Writing a picture failed (the message names the file).
    #[error(transparent)]
    Picture(#[from] crate::picture::PictureError),
    /// A Vulkan failure while rendering.
    #[error("{context}: {cause}")]
    Device {
        /// What the renderer was doing.
        context: String,
        /// The device error.
        cause: crate::gpu::GpuError,
    },
}

impl crate::gpu::GpuFailure for SpectralError {
    fn gpu_error(&self) -> Option<&crate::gpu::GpuError> {
        match self {
            Self::Device { cause, .. } => Some(cause),
            _ => None,
        }
    }
}

impl SpectralError {
    /// Wraps a device error with what the renderer was doing.
    pub fn device(context: &str) -> impl Fn(crate::gpu::GpuError) -> Self + '_ {
        move |cause| Self::Device { context: context.to_owned(), cause }
    }
}
