//! MFEM's numbering of a quadrilateral or hexahedral mesh's H1 degrees of freedom
//! (vertices, then edges and faces by first appearance, then interiors), and each element's
//! DOFs gathered into this crate's lexicographic order ([`super::mfem`] reads the files;
//! triangles and tetrahedra: [`super::mfem_simplex`]).

use super::basis::NodeSet;
use super::error::SpectralError;
use super::mfem::{Collection, MfemMesh};

/// MFEM's local edges of a quadrilateral (`Geometry::Constants<SQUARE>::Edges`).
const QUAD_EDGES: [[usize; 2]; 4] = [[0, 1], [1, 2], [2, 3], [3, 0]];
/// MFEM's local edges of a hexahedron.
const HEX_EDGES: [[usize; 2]; 12] =
    [[0, 1], [1, 2], [3, 2], [0, 3], [4, 5], [5, 6], [7, 6], [4, 7], [0, 4], [1, 5], [2, 6], [3, 7]];
/// MFEM's local faces of a hexahedron (`FaceVert`), each walked from its first vertex.
const HEX_FACES: [[usize; 4]; 6] =
    [[3, 2, 1, 0], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]];
/// The corner (0 or 1 per axis) of each local vertex in the reference cell.
const CORNERS: [[usize; 3]; 8] =
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];

/// The mesh's entities as MFEM numbers them: edges and faces by first appearance, walking
/// the elements in order and each element's local edges (faces) in MFEM's order; a global
/// edge runs from its lower to its higher vertex id; a global face keeps the vertex order of
/// the first element that has it.
pub(super) struct Topology<'a> {
    mesh: &'a MfemMesh,
    /// Per element, its local edges' global numbers.
    element_edges: Vec<Vec<usize>>,
    /// Per element, its local faces' global numbers (hexahedra).
    element_faces: Vec<Vec<usize>>,
    /// Each global face's vertices in its own frame.
    faces: Vec<[usize; 4]>,
    edges: usize,
}

impl<'a> Topology<'a> {
    pub(super) fn new(mesh: &'a MfemMesh) -> Self {
        let hex = mesh.dim == 3;
        let local_edges: &[[usize; 2]] = if hex { &HEX_EDGES } else { &QUAD_EDGES };
        let mut edge_ids = std::collections::HashMap::new();
        let mut face_ids = std::collections::HashMap::new();
        let mut faces = Vec::new();
        let mut element_edges = Vec::with_capacity(mesh.elements.len());
        let mut element_faces = Vec::with_capacity(mesh.elements.len());
        for v in &mesh.elements {
            element_edges.push(
                local_edges
                    .iter()
                    .map(|&[a, b]| {
                        let key = (v[a].min(v[b]), v[a].max(v[b]));
                        let next = edge_ids.len();
                        *edge_ids.entry(key).or_insert(next)
                    })
                    .collect(),
            );
            if hex {
                element_faces.push(
                    HEX_FACES
                        .iter()
                        .map(|f| {
                            let verts = f.map(|k| v[k]);
                            let mut key = verts;
                            key.sort_unstable();
                            let next = faces.len();
                            let id = *face_ids.entry(key).or_insert(next);
                            if id == next {
                                faces.push(verts);
                            }
                            id
                        })
                        .collect(),
                );
            }
        }
        Self { mesh, element_edges, element_faces, faces, edges: edge_ids.len() }
    }

    /// Global DOFs of a space of collection `c`.
    pub(super) fn dof_count(&self, c: &Collection) -> Result<usize, SpectralError> {
        let (p, d) = (c.order, self.mesh.dim);
        let elements = self.mesh.elements.len();
        if !c.continuous {
            return Ok(elements * (p + 1).pow(d));
        }
        if c.set == NodeSet::Gauss {
            return Err(SpectralError::File {
                path: self.mesh.path.clone(),
                detail: format!("{}: an H1 space needs nodes at the endpoints", c.name),
            });
        }
        let n = p - 1;
        Ok(self.mesh.vertex_count + self.edges * n + self.faces.len() * n * n + elements * n.pow(d))
    }

    /// Element `e`'s global DOFs of collection `c` in lexicographic order (ξ fastest).
    pub(super) fn element_dofs(&self, c: &Collection, e: usize) -> Vec<usize> {
        let p = c.order;
        let d = self.mesh.dim as usize;
        let m = p + 1;
        let count = m.pow(d as u32);
        if !c.continuous {
            return (0..count).map(|k| e * count + k).collect();
        }
        let n = p - 1;
        let v = &self.mesh.elements[e];
        let nv = self.mesh.vertex_count;
        let edge_base = nv;
        let face_base = edge_base + self.edges * n;
        let body_base = face_base + self.faces.len() * n * n;
        let corners = if d == 3 { 8 } else { 4 };
        let corner_of = |k: usize| [CORNERS[k][0] * p, CORNERS[k][1] * p, CORNERS[k][2] * p];
        let local_edges: &[[usize; 2]] = if d == 3 { &HEX_EDGES } else { &QUAD_EDGES };
        (0..count)
            .map(|flat| {
                let ijk = [flat % m, (flat / m) % m, if d == 3 { flat / (m * m) } else { 0 }];
                let on = |a: usize| ijk[a] == 0 || ijk[a] == p;
                let boundary_axes = (0..d).filter(|&a| on(a)).count();
                match d - boundary_axes {
                    // A vertex.
                    0 => v[(0..corners).find(|&k| corner_of(k) == ijk).expect("a corner")],
                    // On an edge: the local edge whose ends agree on the fixed axes.
                    1 => {
                        let free = (0..d).find(|&a| !on(a)).expect("one free axis");
                        let (k, &[a, b]) = local_edges
                            .iter()
                            .enumerate()
                            .find(|(_, [a, b])| {
                                let (ca, cb) = (corner_of(*a), corner_of(*b));
                                (0..d).all(|x| x == free || (ca[x] == ijk[x] && cb[x] == ijk[x]))
                            })
                            .expect("an edge");
                        // Position along the local edge, from its first vertex.
                        let t = ijk[free].abs_diff(corner_of(a)[free]);
                        let j = t - 1;
                        let j = if v[a] < v[b] { j } else { n - 1 - j };
                        edge_base + self.element_edges[e][k] * n + j
                    }
                    // On a face (hexahedra): the local face whose corners share the fixed axis.
                    2 if d == 3 => {
                        let fixed = (0..3).find(|&a| on(a)).expect("one fixed axis");
                        let (k, f) = HEX_FACES
                            .iter()
                            .enumerate()
                            .find(|(_, f)| f.iter().all(|&c| corner_of(c)[fixed] == ijk[fixed]))
                            .expect("a face");
                        // The point's coordinates (s, t) ∈ [0, p]² in the global face's frame:
                        // each global corner's position in the lattice, then the affine frame.
                        let global = self.faces[self.element_faces[e][k]];
                        let lattice = |g: usize| {
                            corner_of(f[f.iter().position(|&c| v[c] == g).expect("shared vertex")])
                        };
                        let (o, s_end, t_end) = (lattice(global[0]), lattice(global[1]), lattice(global[3]));
                        let along = |end: [usize; 3]| {
                            let axis = (0..3).find(|&x| end[x] != o[x]).expect("an edge of the face");
                            ijk[axis].abs_diff(o[axis])
                        };
                        let (s, t) = (along(s_end), along(t_end));
                        face_base + self.element_faces[e][k] * n * n + (s - 1) + (t - 1) * n
                    }
                    // Interior: lexicographic over 1..p−1.
                    _ => {
                        let inner: usize = (0..d).rev().fold(0, |acc, a| acc * n + (ijk[a] - 1));
                        body_base + e * n.pow(d as u32) + inner
                    }
                }
            })
            .collect()
    }
}
