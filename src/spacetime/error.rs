//! Errors of the spacetime module: bad data name the element (and the file, when read).

use std::path::PathBuf;

/// What can go wrong with a spacetime data set.
#[derive(Debug, thiserror::Error)]
pub enum SpacetimeError {
    /// A tetrahedron references a vertex that does not exist.
    #[error("element {element}: vertex index {index} is out of range ({vertices} vertices)")]
    BadIndex {
        /// The element.
        element: usize,
        /// The index.
        index: u64,
        /// Number of vertices.
        vertices: usize,
    },
    /// A tetrahedron with (numerically) zero spacetime volume (seed 003 §4.1 assumes none).
    #[error("element {element}: degenerate tetrahedron (spacetime volume {volume:e})")]
    Degenerate {
        /// The element.
        element: usize,
        /// Its signed volume.
        volume: f64,
    },
    /// A NaN or infinity in a vertex, frame, material or coefficient.
    #[error("element {element}: {what} is not finite")]
    NotFinite {
        /// The element (or vertex, for vertex data).
        element: usize,
        /// Which value.
        what: String,
    },
    /// A frame with a non-positive extent, or a material with non-positive μ or density.
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
    /// A problem reading or writing a file.
    #[error("{path}: {detail}")]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        detail: String,
    },
    /// More elements can be cut by one time plane than one storage binding holds.
    #[error(
        "{active} elements may be cut by this time plane; one device binding holds {limit} \
         (elements longer in time than needed make the active range long)"
    )]
    TooManyActive {
        /// Elements in the active range.
        active: usize,
        /// Records per binding.
        limit: usize,
    },
    /// The slice at a time still overflowed its output buffers after they were grown to what
    /// it asked for (a bug in the slicer's counts, not bad data).
    #[error("the slice at t = {t} still overflowed its buffers after {rounds} rounds of growing them")]
    SliceOverflow {
        /// The time.
        t: f64,
        /// Rounds tried.
        rounds: usize,
    },
    /// A request the data sets cannot satisfy (an unknown data set, a count out of range, a
    /// time outside the span), in words the user can act on.
    #[error("{0}")]
    Request(String),
    /// Writing a picture failed (the message names the file).
    #[error(transparent)]
    Picture(#[from] crate::picture::PictureError),
    /// A device failure.
    #[error("{context}: {cause}")]
    Device {
        /// What was being done.
        context: String,
        /// The failure.
        cause: crate::gpu::GpuError,
    },
}

impl crate::gpu::GpuFailure for SpacetimeError {
    fn gpu_error(&self) -> Option<&crate::gpu::GpuError> {
        match self {
            Self::Device { cause, .. } => Some(cause),
            _ => None,
        }
    }
}

impl SpacetimeError {
    /// Wraps a device failure met while doing `context` (for `map_err`).
    pub fn device(context: &str) -> impl FnOnce(crate::gpu::GpuError) -> Self + '_ {
        move |cause| Self::Device { context: context.to_string(), cause }
    }
}
