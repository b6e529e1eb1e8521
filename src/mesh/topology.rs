//! Face–cell connectivity of a [`SimplexMesh`]: every face (the facet opposite one vertex of a
//! cell) gets one global orientation, outward from its first cell; each cell sees it with sign
//! σ = +1 (first cell) or −1 (second). Faces with one cell are boundary faces; with a periodic
//! axis, the faces on its two sides are matched geometrically into wrap faces.

use std::collections::HashMap;

use super::{MeshError, SimplexMesh};

/// A periodic axis: vertices on the two sides `min` and `min + period` are identified.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic {
    /// The axis (0 = x).
    pub axis: usize,
}

/// What a face is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceKind {
    /// Between two cells.
    Interior,
    /// Between two cells across the periodic boundary (the cells see translated copies).
    Wrap,
    /// On the domain boundary: one cell.
    Boundary,
}

/// No second cell.
pub const NO_CELL: u32 = u32::MAX;

/// Faces, signs and neighbours of a mesh (fixed for its whole deformation).
#[derive(Clone, Debug)]
pub struct Topology {
    dim: usize,
    /// The two cells of each face (`NO_CELL` second for a boundary face); the face is oriented
    /// outward from the first.
    face_cells: Vec<[u32; 2]>,
    /// The face's local index (opposite vertex) in each of its cells.
    face_local: Vec<[u8; 2]>,
    kinds: Vec<FaceKind>,
    /// `dim + 1` faces per cell, in local order (face k is opposite vertex k).
    cell_faces: Vec<u32>,
    /// σ for each (cell, local face): +1 if the face's orientation is outward for the cell.
    cell_signs: Vec<f64>,
    boundary: Vec<u32>,
    /// Each vertex's periodic representative (itself unless it is on the upper side).
    representative: Vec<u32>,
}

impl Topology {
    /// Builds the topology, matching the two sides of `periodic` (if any) geometrically
    /// (tolerance 1e-9 of the mesh's extent). Refuses non-manifold faces and unmatched
    /// periodic vertices.
    pub fn new(mesh: &SimplexMesh, periodic: Option<Periodic>) -> Result<Self, MeshError> {
        let dim = mesh.dim();
        let nv = mesh.vertex_count();
        let representative = match periodic {
            Some(p) => match_periodic(mesh, p.axis)?,
            None => (0..nv as u32).collect(),
        };
        let nc = mesh.cell_count();
        let mut index: HashMap<[u32; 3], u32> = HashMap::with_capacity(nc * (dim + 1) / 2 + 16);
        let mut face_cells: Vec<[u32; 2]> = Vec::new();
        let mut face_local: Vec<[u8; 2]> = Vec::new();
        let mut cell_faces = vec![0u32; nc * (dim + 1)];
        let mut cell_signs = vec![0.0; nc * (dim + 1)];
        for c in 0..nc {
            let cell = mesh.cell(c);
            for k in 0..=dim {
                let mut key = [u32::MAX; 3];
                let mut n = 0;
                for (i, &v) in cell.iter().enumerate() {
                    if i != k {
                        key[n] = representative[v as usize];
                        n += 1;
                    }
                }
                key[..dim].sort_unstable();
                let slot = c * (dim + 1) + k;
                match index.get(&key) {
                    None => {
                        let f = face_cells.len() as u32;
                        index.insert(key, f);
                        face_cells.push([c as u32, NO_CELL]);
                        face_local.push([k as u8, 0]);
                        cell_faces[slot] = f;
                        cell_signs[slot] = 1.0;
                    }
                    Some(&f) => {
                        let fc = &mut face_cells[f as usize];
                        if fc[1] != NO_CELL {
                            return Err(MeshError::NonManifold {
                                vertices: key[..dim].to_vec(),
                                cells: vec![fc[0] as usize, fc[1] as usize, c],
                            });
                        }
                        fc[1] = c as u32;
                        face_local[f as usize][1] = k as u8;
                        cell_faces[slot] = f;
                        cell_signs[slot] = -1.0;
                    }
                }
            }
        }
        let mut kinds = Vec::with_capacity(face_cells.len());
        let mut boundary = Vec::new();
        for (f, (fc, fl)) in face_cells.iter().zip(&face_local).enumerate() {
            if fc[1] == NO_CELL {
                kinds.push(FaceKind::Boundary);
                boundary.push(f as u32);
                continue;
            }
            let verts = |c: u32, k: u8| {
                let mut v: Vec<u32> = mesh
                    .cell(c as usize)
                    .iter()
                    .enumerate()
                    .filter(|&(i, _)| i != k as usize)
                    .map(|(_, &v)| v)
                    .collect();
                v.sort_unstable();
                v
            };
            kinds.push(if verts(fc[0], fl[0]) == verts(fc[1], fl[1]) {
                FaceKind::Interior
            } else {
                FaceKind::Wrap
            });
        }
        if let Some(p) = periodic {
            check_sides_paired(mesh, p.axis, &boundary, &face_cells, &face_local)?;
        }
        Ok(Self { dim, face_cells, face_local, kinds, cell_faces, cell_signs, boundary, representative })
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_cells.len()
    }

    /// The cells of face `f`: `[first, second]`, second `NO_CELL` on the boundary.
    pub fn face_cells(&self, f: usize) -> [u32; 2] {
        self.face_cells[f]
    }

    /// The local index of face `f` in each of its cells.
    pub fn face_local(&self, f: usize) -> [u8; 2] {
        self.face_local[f]
    }

    /// What face `f` is.
    pub fn kind(&self, f: usize) -> FaceKind {
        self.kinds[f]
    }

    /// The global face opposite local vertex `k` of cell `c`.
    pub fn cell_face(&self, c: usize, k: usize) -> usize {
        self.cell_faces[c * (self.dim + 1) + k] as usize
    }

    /// σ of (cell `c`, local face `k`): +1 if the face's global orientation is outward for `c`.
    pub fn sign(&self, c: usize, k: usize) -> f64 {
        self.cell_signs[c * (self.dim + 1) + k]
    }

    /// The cell across local face `k` of cell `c`, if any (across the periodic boundary too).
    pub fn neighbour(&self, c: usize, k: usize) -> Option<usize> {
        let f = self.cell_face(c, k);
        let [a, b] = self.face_cells[f];
        if b == NO_CELL {
            None
        } else if a as usize == c && b as usize != c {
            Some(b as usize)
        } else {
            Some(a as usize)
        }
    }

    /// The boundary faces, ascending (the rows of the boundary selector D).
    pub fn boundary_faces(&self) -> &[u32] {
        &self.boundary
    }

    /// Each vertex's periodic representative.
    pub fn representative(&self) -> &[u32] {
        &self.representative
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.cell_faces.len() / (self.dim + 1)
    }

    /// The spatial dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }
}

/// Refuses a boundary face lying in either periodic side: its vertices are matched with the
/// other side's, but no face there joins the same vertices (the two sides are triangulated
/// differently), so the flow would see a wall where the mesh says it wraps.
fn check_sides_paired(
    mesh: &SimplexMesh,
    axis: usize,
    boundary: &[u32],
    face_cells: &[[u32; 2]],
    face_local: &[[u8; 2]],
) -> Result<(), MeshError> {
    let dim = mesh.dim();
    let (lo, hi) = mesh.bounds();
    let extent = (0..dim).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let tol = 1e-9 * extent.max(f64::MIN_POSITIVE);
    for &f in boundary {
        let [c, _] = face_cells[f as usize];
        let k = face_local[f as usize][0] as usize;
        let vertices: Vec<u32> =
            mesh.cell(c as usize).iter().enumerate().filter(|&(i, _)| i != k).map(|(_, &v)| v).collect();
        for side in [lo[axis], hi[axis]] {
            if vertices.iter().all(|&v| (mesh.point(v as usize)[axis] - side).abs() <= tol) {
                return Err(MeshError::Structure(format!(
                    "periodic axis {axis}: the face of vertices {vertices:?} on the side at {side} has no matching face on the other side (its vertices match, but the two sides' faces differ)"
                )));
            }
        }
    }
    Ok(())
}

/// Pairs the vertices on the upper side of `axis` with those on the lower side.
fn match_periodic(mesh: &SimplexMesh, axis: usize) -> Result<Vec<u32>, MeshError> {
    let dim = mesh.dim();
    if axis >= dim {
        return Err(MeshError::Structure(format!(
            "periodic axis {axis} in a {dim}D mesh (the axes are 0 to {})",
            dim - 1
        )));
    }
    let (lo, hi) = mesh.bounds();
    let extent = (0..dim).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let tol = 1e-9 * extent.max(f64::MIN_POSITIVE);
    let nv = mesh.vertex_count();
    let lower: Vec<usize> = (0..nv).filter(|&v| (mesh.point(v)[axis] - lo[axis]).abs() <= tol).collect();
    let upper: Vec<usize> = (0..nv).filter(|&v| (mesh.point(v)[axis] - hi[axis]).abs() <= tol).collect();
    // Sort the lower side by the other coordinates and find each upper vertex by bisection.
    let others = |v: usize| -> [f64; 2] {
        let p = mesh.point(v);
        let mut o = [0.0; 2];
        let mut n = 0;
        for (k, &x) in p.iter().enumerate().take(dim) {
            if k != axis {
                o[n] = x;
                n += 1;
            }
        }
        o
    };
    let mut sorted: Vec<(usize, [f64; 2])> = lower.iter().map(|&v| (v, others(v))).collect();
    sorted.sort_by(|a, b| a.1[0].total_cmp(&b.1[0]).then(a.1[1].total_cmp(&b.1[1])));
    let mut representative: Vec<u32> = (0..nv as u32).collect();
    let mut used = vec![false; sorted.len()];
    for &u in &upper {
        let o = others(u);
        let start = sorted.partition_point(|e| e.1[0] < o[0] - tol);
        let found = sorted[start..]
            .iter()
            .enumerate()
            .take_while(|(_, e)| e.1[0] <= o[0] + tol)
            .find(|(_, e)| (e.1[1] - o[1]).abs() <= tol)
            .map(|(i, _)| start + i);
        match found {
            Some(i) if !used[i] => {
                used[i] = true;
                representative[u] = sorted[i].0 as u32;
            }
            _ => {
                return Err(MeshError::UnmatchedPeriodic {
                    vertex: u,
                    position: mesh.point(u)[..dim].to_vec(),
                    axis,
                })
            }
        }
    }
    if let Some(i) = used.iter().position(|&u| !u) {
        let v = sorted[i].0;
        return Err(MeshError::UnmatchedPeriodic {
            vertex: v,
            position: mesh.point(v)[..dim].to_vec(),
            axis,
        });
    }
    Ok(representative)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three unit cubes in a row along x, each in five tetrahedra (four corners cut off a
    /// central one), the middle one mirrored so the faces between them conform: the x = 0 side
    /// is split along (0,0,0)–(0,1,1), the x = 3 side along (3,1,0)–(3,0,1), so the sides'
    /// vertices match across x but their faces do not.
    fn five_tet_cubes() -> SimplexMesh {
        let v = |i: u32, j: u32, k: u32| i + 4 * (j + 2 * k);
        let g =
            (0..16u32).flat_map(|n| [f64::from(n % 4), f64::from((n / 4) % 2), f64::from(n / 8)]).collect();
        let local = [
            [[0, 0, 0], [1, 1, 0], [1, 0, 1], [0, 1, 1]],
            [[1, 0, 0], [0, 0, 0], [1, 1, 0], [1, 0, 1]],
            [[0, 1, 0], [0, 0, 0], [1, 1, 0], [0, 1, 1]],
            [[0, 0, 1], [0, 0, 0], [1, 0, 1], [0, 1, 1]],
            [[1, 1, 1], [1, 1, 0], [1, 0, 1], [0, 1, 1]],
        ];
        let mut cells = Vec::new();
        for cube in 0..3u32 {
            for tet in &local {
                for [a, b, c] in tet {
                    let a = if cube == 1 { 1 - a } else { *a };
                    cells.push(v(cube + a, *b, *c));
                }
            }
        }
        SimplexMesh::new(3, g, cells).expect("the cubes")
    }

    #[test]
    fn periodic_sides_must_pair_faces_not_only_vertices() {
        let cube = five_tet_cubes();
        assert_eq!(Topology::new(&cube, None).expect("open").boundary_faces().len(), 28);
        let e = Topology::new(&cube, Some(Periodic { axis: 0 })).expect_err("sides differ").to_string();
        assert!(e.contains("periodic axis 0") && e.contains("no matching face"), "{e}");
        let e = Topology::new(&cube, Some(Periodic { axis: 5 })).expect_err("no axis 5").to_string();
        assert!(e.contains("axes are 0 to 2"), "{e}");
    }
}
