//! MFEM's triangles (`Geometry::TRIANGLE` = 2) and tetrahedra (`Geometry::TETRAHEDRON` = 4):
//! straight or curved meshes and H1, H1Pos and L2 GridFunctions on them, turned into this
//! crate's Lagrange simplices ([`super::Shape::Triangle`], [`super::Shape::Tetrahedron`]) on equispaced
//! nodes — the same polynomials, so GLVis users see their simplex data exactly.
//!
//! **MFEM's local DOFs.** Every nodal DOF of an MFEM simplex element of order p is named by
//! integer weights `w` over the element's vertices (Σ w = p), and sits at barycentric
//! coordinates `λ_v = x[w_v] / Σ_u x[w_u]`, with x the collection's 1D points on [0, 1]
//! (Gauss–Lobatto for `H1_`, Gauss–Legendre for `L2_`, as named by `@U`, `T1`, `T4`, …): the
//! construction of `H1_TriangleElement`, `H1_TetrahedronElement`, `L2_TriangleElement` and
//! `L2_TetrahedronElement`. H1 elements list the vertices, then each local edge (a, b)
//! (weights p − i on a, i on b, i = 1..p−1), then on tetrahedra each local face
//! (f₀, f₁, f₂) (weights p − i − j, i, j, j outer), then the interior (j outer, i inner; on
//! tetrahedra k outermost); L2 elements list every multi-index, k, j outer, i inner.
//! `H1Pos_` (Bernstein) elements name their coefficients by the same weights: the
//! coefficient of `B_w`. [`local_dofs`] lists them; `tests/spectral_mfem_files.rs` checks
//! the points against MFEM 4.10's own (`scripts/mfem-fixtures.py`, `simplex_nodes.json`).
//!
//! **Global numbering (H1).** Vertices, then edges, then faces, then interiors, each entity in
//! order of first appearance walking the elements and their local edges and faces (MFEM's
//! local edges and faces are `Geometry::Constants<…>::Edges` and `FaceVert`). A global edge runs
//! from its lower vertex id to its higher, and its DOF t has weight t + 1 on the higher; a
//! global face keeps the vertex order (g₀, g₁, g₂) of the first element that has it, and its
//! DOF (i, j) has weights i on g₁ and j on g₂. So each local DOF finds its global one by its
//! weights on the shared vertices, whatever the element's orientation.
//!
//! **To our nodes.** [`ToLattice`] maps an element's local values to the values at our
//! equispaced lattice of order N ≥ p (the higher of the geometry's and the fields' orders,
//! so the elements are isoparametric): for nodal sets it interpolates (the inverse of the
//! collocation matrix of our order-p Lagrange basis at MFEM's points, then our basis at the
//! order-N lattice), for Bernstein it sums the Bernstein polynomials at the lattice.

use faer::linalg::solvers::Solve;

use super::basis::{Basis1d, NodeSet};
use super::error::SpectralError;
use super::mesh::{Field, SpectralMesh};
use super::mfem::{check_nodes, check_scalar_step, component, Collection, GridFunction, MfemMesh};
use super::simplex::{
    apply, basis, bernstein_basis, lattice, per_component, SimplexShape, MAX_SIMPLEX_ORDER,
};

/// MFEM's local edges of a triangle (`Geometry::Constants<TRIANGLE>::Edges`).
const TRIANGLE_EDGES: [[usize; 2]; 3] = [[0, 1], [1, 2], [2, 0]];
/// MFEM's local edges of a tetrahedron.
const TETRA_EDGES: [[usize; 2]; 6] = [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]];
/// MFEM's local faces of a tetrahedron (`FaceVert`).
const TETRA_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]];

fn simplex_shape(mesh: &MfemMesh) -> SimplexShape {
    if mesh.dim == 2 {
        SimplexShape::Triangle
    } else {
        SimplexShape::Tetrahedron
    }
}

/// The local DOFs of an MFEM simplex element of order `p` (H1 when `continuous`, else L2) in
/// MFEM's order, each as its weights over the element's vertices (entries 0..=d used; see the
/// module docs).
pub fn local_dofs(shape: SimplexShape, p: usize, continuous: bool) -> Vec<[usize; 4]> {
    let d = shape.dim();
    let mut out = Vec::with_capacity(shape.node_count(p));
    let weights = |pairs: &[(usize, usize)]| {
        let mut w = [0; 4];
        for &(v, x) in pairs {
            w[v] += x;
        }
        w
    };
    // Every multi-index with entries ≥ `low` on vertices 1..=d, k outer, j, i inner.
    let lexicographic = |low: usize, out: &mut Vec<[usize; 4]>| {
        let top = if d == 3 { p } else { 0 };
        for k in (if d == 3 { low } else { 0 })..=top {
            for j in low..=p {
                for i in low..=p {
                    if i + j + k + low <= p {
                        out.push(weights(&[(0, p - i - j - k), (1, i), (2, j), (3, k)]));
                    }
                }
            }
        }
    };
    if !continuous {
        lexicographic(0, &mut out);
        return out;
    }
    for v in 0..=d {
        out.push(weights(&[(v, p)]));
    }
    let edges: &[[usize; 2]] = if d == 2 { &TRIANGLE_EDGES } else { &TETRA_EDGES };
    for &[a, b] in edges {
        for i in 1..p {
            out.push(weights(&[(a, p - i), (b, i)]));
        }
    }
    if d == 3 {
        for [f0, f1, f2] in TETRA_FACES {
            for j in 1..p {
                for i in 1..p - j {
                    out.push(weights(&[(f0, p - i - j), (f1, i), (f2, j)]));
                }
            }
        }
    }
    // The interior: every entry ≥ 1 (so the remainder on vertex 0 too).
    lexicographic(1, &mut out);
    out
}

/// A collection's local DOFs ([`local_dofs`]) and where the interior ones begin (H1 lists them
/// last), formed once per collection rather than per element.
struct LocalDofs {
    weights: Vec<[usize; 4]>,
    interior_from: usize,
}

impl LocalDofs {
    fn new(shape: SimplexShape, c: &Collection) -> Self {
        let weights = local_dofs(shape, c.order, c.continuous);
        let d = shape.dim();
        let interior_from = weights.iter().position(|w| (0..=d).all(|a| w[a] > 0)).unwrap_or(weights.len());
        Self { weights, interior_from }
    }
}

/// The reference point (r₀, r₁[, r₂]) = (λ₁, λ₂[, λ₃]) of the DOF of weights `w`, with
/// `λ_v = x[w_v] / Σ_u x[w_u]` over the 1D points `x`.
pub fn dof_point(shape: SimplexShape, w: &[usize; 4], x: &[f64]) -> [f64; 3] {
    let d = shape.dim();
    let total: f64 = (0..=d).map(|v| x[w[v]]).sum();
    std::array::from_fn(|a| if a < d { x[w[a + 1]] / total } else { 0.0 })
}

/// The multi-index of [`super::simplex`] (entries 0..d on the axes, entry d the remainder)
/// of weights `w` over the vertices (entry 0 on vertex 0).
fn multi_index(shape: SimplexShape, w: &[usize; 4]) -> [usize; 4] {
    let d = shape.dim();
    std::array::from_fn(|a| {
        if a < d {
            w[a + 1]
        } else if a == d {
            w[0]
        } else {
            0
        }
    })
}

/// From an MFEM element's local values (one collection) to our equispaced values of order
/// `target` (see the module docs): a matrix of `lattice × local` entries, formed once.
pub struct ToLattice {
    local: usize,
    matrix: Vec<f64>,
}

impl ToLattice {
    /// The map for collection `c` on `shape`, to order `target` ≥ `c.order`.
    pub fn new(shape: SimplexShape, c: &Collection, target: usize) -> Result<Self, SpectralError> {
        let p = c.order;
        let dofs = local_dofs(shape, p, c.continuous);
        let ours = lattice(shape, target);
        let at = |b: &[usize; 4]| -> [f64; 3] {
            std::array::from_fn(|a| if a < shape.dim() { b[a] as f64 / target as f64 } else { 0.0 })
        };
        let local = dofs.len();
        let mut matrix = Vec::with_capacity(ours.len() * local);
        if c.set == NodeSet::Bernstein {
            let indices: Vec<[usize; 4]> = dofs.iter().map(|w| multi_index(shape, w)).collect();
            for node in &ours {
                matrix.extend(bernstein_basis(shape, p, &indices, &at(node)).into_iter().map(|(v, _)| v));
            }
            return Ok(Self { local, matrix });
        }
        let x = Basis1d::new(c.set, p)?.nodes;
        let order_p = lattice(shape, p);
        // V[k][i] = L_i(point of local DOF k), our order-p Lagrange basis; its inverse takes
        // local values to our order-p values.
        let rows = |points: &mut dyn Iterator<Item = [f64; 3]>, count: usize| {
            let mut m = faer::Mat::<f64>::zeros(count, local);
            for (k, r) in points.enumerate() {
                for (i, (value, _)) in basis(shape, p, &order_p, &r).into_iter().enumerate() {
                    m[(k, i)] = value;
                }
            }
            m
        };
        let v = rows(&mut dofs.iter().map(|w| dof_point(shape, w, &x)), local);
        let inverse = v.partial_piv_lu().solve(faer::Mat::<f64>::identity(local, local));
        // E[j][i] = L_i(our order-`target` node j).
        let e = rows(&mut ours.iter().map(at), ours.len());
        let product = e * inverse;
        for j in 0..ours.len() {
            matrix.extend((0..local).map(|k| product[(j, k)]));
        }
        if matrix.iter().any(|m| !m.is_finite()) {
            return Err(SpectralError::Missing(format!("{}: its nodes are not unisolvent", c.name)));
        }
        Ok(Self { local, matrix })
    }

    /// Our lattice values from the element's local `values` (MFEM's order).
    pub fn apply(&self, values: &[f64]) -> Vec<f64> {
        apply(self.local, &self.matrix, values)
    }
}

/// The mesh's edges and faces as MFEM numbers them (module docs).
struct Topology {
    /// Global edge number of each (lower, higher) vertex pair.
    edges: std::collections::HashMap<(usize, usize), usize>,
    /// Global face number of each sorted vertex triple, and each face's own vertex order.
    faces: std::collections::HashMap<[usize; 3], usize>,
    face_vertices: Vec<[usize; 3]>,
}

impl Topology {
    fn new(mesh: &MfemMesh) -> Self {
        let edge_list: &[[usize; 2]] = if mesh.dim == 2 { &TRIANGLE_EDGES } else { &TETRA_EDGES };
        let (mut edges, mut faces) = (std::collections::HashMap::new(), std::collections::HashMap::new());
        let mut face_vertices = Vec::new();
        for v in &mesh.elements {
            for &[a, b] in edge_list {
                let next = edges.len();
                edges.entry((v[a].min(v[b]), v[a].max(v[b]))).or_insert(next);
            }
            if mesh.dim == 3 {
                for f in TETRA_FACES {
                    let verts = f.map(|k| v[k]);
                    let mut key = verts;
                    key.sort_unstable();
                    let next = face_vertices.len();
                    if *faces.entry(key).or_insert(next) == next {
                        face_vertices.push(verts);
                    }
                }
            }
        }
        Self { edges, faces, face_vertices }
    }

    /// Global DOFs of collection `c` (order p): H1 `V + E(p−1) + F(p−1)(p−2)/2 + K·interior`,
    /// L2 `K·local`.
    fn dof_count(&self, mesh: &MfemMesh, c: &Collection) -> usize {
        let shape = simplex_shape(mesh);
        let p = c.order;
        let elements = mesh.elements.len();
        if !c.continuous {
            return elements * shape.node_count(p);
        }
        let face = if p >= 3 { SimplexShape::Triangle.node_count(p - 3) } else { 0 };
        let interior = match shape {
            SimplexShape::Triangle => face,
            SimplexShape::Tetrahedron if p >= 4 => SimplexShape::Tetrahedron.node_count(p - 4),
            SimplexShape::Tetrahedron => 0,
        };
        mesh.vertex_count + self.edges.len() * (p - 1) + self.face_vertices.len() * face + elements * interior
    }

    /// Element `e`'s global DOFs of collection `c` (its local DOFs `local`), in MFEM's local
    /// order.
    fn element_dofs(&self, mesh: &MfemMesh, c: &Collection, local: &LocalDofs, e: usize) -> Vec<usize> {
        let p = c.order;
        let count = local.weights.len();
        if !c.continuous {
            return (e * count..(e + 1) * count).collect();
        }
        let d = simplex_shape(mesh).dim();
        let v = &mesh.elements[e];
        let face = if p >= 3 { SimplexShape::Triangle.node_count(p - 3) } else { 0 };
        let edge_base = mesh.vertex_count;
        let face_base = edge_base + self.edges.len() * (p - 1);
        let body_base = face_base + self.face_vertices.len() * face;
        let interior = count - local.interior_from;
        // Position of the face DOF (i, j) among (j outer, i inner; i, j ≥ 1, i + j < p).
        let face_index = |i: usize, j: usize| (1..j).map(|jj| p - 1 - jj).sum::<usize>() + (i - 1);
        local
            .weights
            .iter()
            .enumerate()
            .map(|(k, w)| {
                let on: Vec<usize> = (0..=d).filter(|&a| w[a] > 0).collect();
                let weight_on = |vertex: usize| on.iter().find(|&&a| v[a] == vertex).map_or(0, |&a| w[a]);
                match on.len() {
                    1 => v[on[0]],
                    2 => {
                        let (a, b) = (v[on[0]].min(v[on[1]]), v[on[0]].max(v[on[1]]));
                        edge_base + self.edges[&(a, b)] * (p - 1) + weight_on(b) - 1
                    }
                    3 if d == 3 => {
                        let mut key = [v[on[0]], v[on[1]], v[on[2]]];
                        key.sort_unstable();
                        let g = self.faces[&key];
                        let frame = self.face_vertices[g];
                        face_base + g * face + face_index(weight_on(frame[1]), weight_on(frame[2]))
                    }
                    _ => body_base + e * interior + (k - local.interior_from),
                }
            })
            .collect()
    }
}

/// Builds the crate's simplex mesh from an MFEM triangle or tetrahedron mesh and scalar
/// GridFunctions on it (see [`super::mfem::to_spectral`], which calls this for simplices).
/// Geometry and fields are raised to one order, the higher of the two (exact). Checks every
/// count against the space it claims; errors name the file and the field.
pub fn to_spectral(
    mesh: &MfemMesh,
    fields: &[(String, Vec<GridFunction>)],
) -> Result<SpectralMesh, SpectralError> {
    let path = &mesh.path;
    let file = |detail: String| SpectralError::File { path: path.clone(), detail };
    let shape = simplex_shape(mesh);
    let topology = Topology::new(mesh);
    let check = |c: &Collection, what: &str, file: &dyn Fn(String) -> SpectralError| {
        if c.dim != mesh.dim {
            return Err(file(format!("{what}: collection {} is {}D on a {}D mesh", c.name, c.dim, mesh.dim)));
        }
        if c.order > MAX_SIMPLEX_ORDER {
            return Err(file(format!(
                "{what}: collection {} is of order {} (simplices of orders 1..={MAX_SIMPLEX_ORDER})",
                c.name, c.order
            )));
        }
        if c.continuous && !c.set.has_endpoints() {
            return Err(file(format!("{what}: {}: an H1 space needs nodes at the vertices", c.name)));
        }
        Ok(())
    };
    let geometry_order = mesh.nodes.as_ref().map_or(1, |n| n.space.collection.order);
    let mut order = geometry_order;
    for (name, steps) in fields {
        for gf in steps {
            check(&gf.space.collection, &format!("field {name:?}"), &|d| SpectralError::File {
                path: gf.path.clone(),
                detail: d,
            })?;
            order = order.max(gf.space.collection.order);
        }
    }
    let per_element = shape.node_count(order);
    let elements = mesh.elements.len();
    // Geometry.
    let mut points = crate::limits::vec_for(elements * per_element, "the geometry's nodes").map_err(file)?;
    match &mesh.nodes {
        None => {
            let linear = Collection {
                continuous: true,
                dim: mesh.dim,
                order: 1,
                set: NodeSet::Equispaced,
                name: "vertices".into(),
            };
            let to = ToLattice::new(shape, &linear, order)?;
            for el in &mesh.elements {
                let corners: Vec<[f64; 3]> = el.iter().map(|&v| mesh.vertices[v]).collect();
                points.extend(per_component(&corners, |v| to.apply(v)));
            }
        }
        Some(nodes) => {
            let c = &nodes.space.collection;
            check(c, "nodes", &file)?;
            let dofs = topology.dof_count(mesh, c);
            let sdim = check_nodes(nodes, dofs)?;
            let to = ToLattice::new(shape, c, order)?;
            let local_dofs = LocalDofs::new(shape, c);
            for e in 0..elements {
                let global = topology.element_dofs(mesh, c, &local_dofs, e);
                let local: Vec<[f64; 3]> = global
                    .iter()
                    .map(|&d| {
                        std::array::from_fn(|k| if k < sdim { component(nodes, dofs, d, k) } else { 0.0 })
                    })
                    .collect();
                points.extend(per_component(&local, |v| to.apply(v)));
            }
        }
    }
    // Fields.
    let mut out_fields = Vec::new();
    for (name, steps) in fields {
        let mut values = Vec::new();
        for (k, gf) in steps.iter().enumerate() {
            let file = |detail: String| SpectralError::File { path: gf.path.clone(), detail };
            let c = &gf.space.collection;
            check_scalar_step(gf, name, k, topology.dof_count(mesh, c))?;
            let to = ToLattice::new(shape, c, order)?;
            let local_dofs = LocalDofs::new(shape, c);
            let mut v = crate::limits::vec_for(elements * per_element, "the field's values").map_err(file)?;
            for e in 0..elements {
                let local: Vec<f64> =
                    topology.element_dofs(mesh, c, &local_dofs, e).iter().map(|&d| gf.values[d]).collect();
                v.extend(to.apply(&local));
            }
            values.push(v);
        }
        out_fields.push(Field {
            name: name.clone(),
            times: (0..values.len()).map(|k| k as f64).collect(),
            steps: values,
        });
    }
    if out_fields.is_empty() {
        return Err(file("no fields".into()));
    }
    let basis = Basis1d::new(NodeSet::Equispaced, order)?;
    SpectralMesh::new(shape.into(), basis.clone(), basis, points, out_fields).map_err(|e| file(e.to_string()))
}
