//! Triangle (2D) and tetrahedral (3D) meshes behind one dimension-generic code path (seed 000
//! §5: "we require that the mesh topology remains constant, but allow continuous deformation of
//! the positions of the mesh vertices denoted g").
//!
//! A [`SimplexMesh`] holds the flat geometry vector `g` (`g[d·v + k]` is coordinate k of vertex
//! v) and the cells (`d + 1` vertex indices each, positively oriented); [`Topology`] adds the
//! faces with one global orientation each, the per-cell outward signs σ, the boundary faces and
//! the periodic (wrap) faces. Generators: [`tunnel`] (the 2D periodic tunnel of §7.1) and
//! [`kuhn`] (boxes of Kuhn simplices for tests and scaling); deformation: [`deform`].

// Numerical code indexes several arrays by the same cell, face or axis.
#![allow(clippy::needless_range_loop)]

pub mod animation;
pub mod budget;
pub mod bvh;
pub mod deform;
mod error;
pub mod geometry;
pub mod gmsh;
pub mod kuhn;
pub mod obj;
pub mod sdf;
pub mod stuffing;
mod topology;
pub mod tunnel;
pub mod untangle;
pub mod volume;

pub use error::MeshError;
pub use geometry::Point;
pub use topology::{FaceKind, Periodic, Topology};

/// A simplicial mesh of fixed topology: vertex positions and cells.
#[derive(Clone, Debug, PartialEq)]
pub struct SimplexMesh {
    dim: usize,
    /// The geometry vector g: `dim` coordinates per vertex.
    g: Vec<f64>,
    /// `dim + 1` vertex indices per cell, positively oriented.
    cells: Vec<u32>,
}

impl SimplexMesh {
    /// A mesh from its geometry vector and cells, checked: dimension 2 or 3, lengths,
    /// indices, finite coordinates. Negatively oriented cells are reordered (two vertices
    /// swapped); flat cells are refused naming the cell.
    pub fn new(dim: usize, g: Vec<f64>, mut cells: Vec<u32>) -> Result<Self, MeshError> {
        if dim != 2 && dim != 3 {
            return Err(MeshError::Structure(format!(
                "dimension {dim}: only 2 (triangles) and 3 (tetrahedra)"
            )));
        }
        if !g.len().is_multiple_of(dim) || !cells.len().is_multiple_of(dim + 1) {
            return Err(MeshError::Structure(format!(
                "{} coordinates and {} cell indices are not multiples of {dim} and {}",
                g.len(),
                cells.len(),
                dim + 1
            )));
        }
        let nv = g.len() / dim;
        if let Some(i) = g.iter().position(|x| !x.is_finite()) {
            return Err(MeshError::NotFinite { vertex: i / dim, axis: i % dim });
        }
        if let Some(i) = cells.iter().position(|&v| v as usize >= nv) {
            return Err(MeshError::Structure(format!(
                "cell {} names vertex {} but the mesh has {nv} vertices",
                i / (dim + 1),
                cells[i]
            )));
        }
        let mut mesh = Self { dim, g, cells: Vec::new() };
        for c in cells.chunks_mut(dim + 1) {
            let p: Vec<Point> = c.iter().map(|&v| mesh.point(v as usize)).collect();
            if geometry::signed_volume(dim, &p) < 0.0 {
                c.swap(0, 1);
            }
        }
        mesh.cells = cells;
        mesh.check_volumes(None)?;
        Ok(mesh)
    }

    /// The spatial dimension (2 or 3).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.g.len() / self.dim
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cells.len() / (self.dim + 1)
    }

    /// The geometry vector g (seed 000 §5).
    pub fn g(&self) -> &[f64] {
        &self.g
    }

    /// All cells' vertex indices, `dim + 1` per cell.
    pub fn cells(&self) -> &[u32] {
        &self.cells
    }

    /// The vertex indices of cell `c`.
    pub fn cell(&self, c: usize) -> &[u32] {
        &self.cells[c * (self.dim + 1)..(c + 1) * (self.dim + 1)]
    }

    /// Vertex `v` as a point (z = 0 in 2D).
    pub fn point(&self, v: usize) -> Point {
        point_of(self.dim, &self.g, v)
    }

    /// The corner points of cell `c` under the geometry vector `g` (same topology).
    pub fn cell_points_at(&self, g: &[f64], c: usize) -> Vec<Point> {
        self.cell(c).iter().map(|&v| point_of(self.dim, g, v as usize)).collect()
    }

    /// The corner points of cell `c`.
    pub fn cell_points(&self, c: usize) -> Vec<Point> {
        self.cell_points_at(&self.g, c)
    }

    /// Signed volumes of every cell under `g` (the diagonal of `V(g)`, Eq. 7).
    pub fn volumes_at(&self, g: &[f64]) -> Vec<f64> {
        (0..self.cell_count())
            .map(|c| geometry::signed_volume(self.dim, &self.cell_points_at(g, c)))
            .collect()
    }

    /// Signed volumes of every cell.
    pub fn volumes(&self) -> Vec<f64> {
        self.volumes_at(&self.g)
    }

    /// Centroid of cell `c`.
    pub fn cell_centroid(&self, c: usize) -> Point {
        geometry::centroid(&self.cell_points(c))
    }

    /// The same topology at new vertex positions, refused if any cell is not positively
    /// oriented (naming `frame` and the cell) or a coordinate is not finite.
    pub fn with_g(&self, g: Vec<f64>, frame: Option<usize>) -> Result<Self, MeshError> {
        self.check_coordinates(&g)?;
        refuse_inverted(&self.volumes_at(&g), frame)?;
        Ok(Self { dim: self.dim, g, cells: self.cells.clone() })
    }

    /// Refuses a geometry vector of the wrong length or with a coordinate that is not finite
    /// (naming the vertex). Its cells' orientation is checked by [`refuse_inverted`] on their
    /// volumes, which callers usually compute anyway.
    pub fn check_coordinates(&self, g: &[f64]) -> Result<(), MeshError> {
        if g.len() != self.g.len() {
            return Err(MeshError::Structure(format!(
                "geometry vector of length {} for a mesh with {} coordinates",
                g.len(),
                self.g.len()
            )));
        }
        match g.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(MeshError::NotFinite { vertex: i / self.dim, axis: i % self.dim }),
            None => Ok(()),
        }
    }

    /// Refuses the first cell whose volume is not positive (see [`refuse_inverted`]).
    pub fn check_volumes(&self, frame: Option<usize>) -> Result<(), MeshError> {
        refuse_inverted(&self.volumes(), frame)
    }

    /// Axis-aligned bounds `(min, max)` of the vertices.
    pub fn bounds(&self) -> (Point, Point) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in 0..self.vertex_count() {
            let p = self.point(v);
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, hi)
    }
}

/// Refuses the first cell of `volumes` that is not positive (relative to the mean cell volume:
/// below 1e-12 of it counts as flat), naming `frame` and the cell.
pub fn refuse_inverted(volumes: &[f64], frame: Option<usize>) -> Result<(), MeshError> {
    let mean = volumes.iter().map(|v| v.abs()).sum::<f64>() / volumes.len().max(1) as f64;
    match volumes.iter().position(|&v| v <= 1e-12 * mean) {
        Some(cell) => Err(MeshError::Inverted { frame, cell, volume: volumes[cell] }),
        None => Ok(()),
    }
}

/// Vertex `v` of the geometry vector `g` in dimension `dim` as a point.
pub fn point_of(dim: usize, g: &[f64], v: usize) -> Point {
    let mut p = [0.0; 3];
    p[..dim].copy_from_slice(&g[dim * v..dim * v + dim]);
    p
}
