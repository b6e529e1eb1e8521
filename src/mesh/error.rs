//! Errors of the mesh module: every one names the element, face, vertex or frame at fault.

/// What can go wrong with a simplicial mesh, its generation or its deformation.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// Arrays that disagree: a cell naming a missing vertex, a length not a multiple of the
    /// dimension.
    #[error("{0}")]
    Structure(String),
    /// A vertex coordinate that is NaN or infinite.
    #[error("vertex {vertex}: coordinate {axis} is not finite")]
    NotFinite {
        /// The vertex.
        vertex: usize,
        /// The coordinate axis (0 = x).
        axis: usize,
    },
    /// A cell with non-positive volume (inverted or flat), optionally in a deformation frame.
    #[error("{}cell {cell}: volume {volume:e} is not positive (inverted or degenerate element)", frame_prefix(*.frame))]
    Inverted {
        /// The deformation frame, when the mesh is one frame of a sequence.
        frame: Option<usize>,
        /// The cell.
        cell: usize,
        /// Its signed volume.
        volume: f64,
    },
    /// A face shared by more than two cells.
    #[error("face with vertices {vertices:?} is shared by cells {cells:?}: the mesh is not a manifold")]
    NonManifold {
        /// The face's vertices.
        vertices: Vec<u32>,
        /// The cells that share it.
        cells: Vec<usize>,
    },
    /// A vertex on one periodic side with no partner on the other.
    #[error("vertex {vertex} at {position:?} on the periodic side of axis {axis} has no partner on the opposite side")]
    UnmatchedPeriodic {
        /// The vertex.
        vertex: usize,
        /// Its position.
        position: Vec<f64>,
        /// The periodic axis.
        axis: usize,
    },
    /// Mesh generation that cannot proceed (bad parameters, a failed triangulation).
    #[error("mesh generation: {0}")]
    Generation(String),
    /// A linear solve that failed (a singular deformation system).
    #[error("{0}")]
    Solve(String),
}

fn frame_prefix(frame: Option<usize>) -> String {
    frame.map(|f| format!("frame {f}: ")).unwrap_or_default()
}
