//! MFEM data (so MFEM users can view their output): meshes in the "MFEM mesh v1.0" text format
//! with straight (`vertices`) or curved (`nodes`) geometry, GridFunction files, and the GLVis
//! "solution" stream that concatenates a mesh and a GridFunction. Quadrilateral (geometry 3)
//! and hexahedral (5) meshes, and triangular (2) and tetrahedral (4) ones
//! ([`super::mfem_simplex`]); H1 and L2 finite element collections, with the basis type read
//! from the collection's name (`H1_2D_P3`: Gauss–Lobatto; `H1Pos_…` / `H1@P_…`: Bernstein;
//! `L2_2D_P3`: Gauss–Legendre; `L2_T1_…`: Gauss–Lobatto; …).
//!
//! Every element's degrees of freedom are gathered into this crate's lexicographic order (ξ
//! fastest): L2 spaces store them element by element; H1 spaces number vertices, then edges,
//! then faces, then interiors, and `mfem_topology::Topology::element_dofs` reassembles each element's tensor
//! grid, reversing edge (and permuting face) DOFs where the element's orientation differs from
//! the global one. Errors name the file and the line or element.

use std::path::{Path, PathBuf};

use super::basis::{Basis1d, NodeSet};
use super::error::SpectralError;
use super::mesh::{Field, Shape, SpectralMesh};

/// MFEM's geometry id of a quadrilateral (`Geometry::SQUARE`).
pub const GEOMETRY_SQUARE: u32 = 3;
/// MFEM's geometry id of a hexahedron (`Geometry::CUBE`).
pub const GEOMETRY_CUBE: u32 = 5;
/// MFEM's geometry id of a triangle (`Geometry::TRIANGLE`).
pub const GEOMETRY_TRIANGLE: u32 = 2;
/// MFEM's geometry id of a tetrahedron (`Geometry::TETRAHEDRON`).
pub const GEOMETRY_TETRAHEDRON: u32 = 4;

/// A finite element collection as named in MFEM files.
#[derive(Clone, Debug, PartialEq)]
pub struct Collection {
    /// H1 (continuous) or L2 (discontinuous).
    pub continuous: bool,
    /// The reference dimension.
    pub dim: u32,
    /// The polynomial order.
    pub order: usize,
    /// The basis's nodes (or Bernstein).
    pub set: NodeSet,
    /// The name as written.
    pub name: String,
}

/// A finite element space header: collection, vector dimension and ordering.
#[derive(Clone, Debug, PartialEq)]
pub struct Space {
    /// The collection.
    pub collection: Collection,
    /// Components per DOF.
    pub vdim: usize,
    /// `Ordering: 1` (byVDIM: the components of one DOF together) or 0 (byNODES: all DOFs of
    /// component 0, then component 1, …).
    pub by_vdim: bool,
}

/// A GridFunction: its space and values.
#[derive(Clone, Debug, PartialEq)]
pub struct GridFunction {
    /// The file it was read from (the mesh's for its nodes, the stream's for GLVis): errors
    /// about its values name it.
    pub path: PathBuf,
    /// The space.
    pub space: Space,
    /// The values, in the space's numbering.
    pub values: Vec<f64>,
}

/// An MFEM mesh: elements (vertex ids), vertex coordinates, and curved nodes if any.
#[derive(Clone, Debug, PartialEq)]
pub struct MfemMesh {
    /// The file.
    pub path: PathBuf,
    /// Reference dimension (2 or 3).
    pub dim: u32,
    /// Every element's MFEM geometry id (one per mesh): [`GEOMETRY_SQUARE`], [`GEOMETRY_CUBE`],
    /// [`GEOMETRY_TRIANGLE`] or [`GEOMETRY_TETRAHEDRON`].
    pub geometry: u32,
    /// Each element's vertices (4 or 8; 3 or 4 for simplices), in MFEM's order.
    pub elements: Vec<Vec<usize>>,
    /// Vertex coordinates (space dimension 2 or 3, padded to 3); empty when `nodes` holds the
    /// geometry.
    pub vertices: Vec<[f64; 3]>,
    /// Number of vertices.
    pub vertex_count: usize,
    /// The curved geometry, a vector GridFunction, when the file has a `nodes` section.
    pub nodes: Option<GridFunction>,
}

fn err(path: &Path, line: usize, detail: impl Into<String>) -> SpectralError {
    SpectralError::File { path: path.to_path_buf(), detail: format!("line {line}: {}", detail.into()) }
}

/// The lines of a text file with their numbers, comments (`#…`) and blank lines skipped.
struct Lines<'a> {
    path: &'a Path,
    lines: Vec<(usize, &'a str)>,
    at: usize,
}

impl<'a> Lines<'a> {
    fn new(path: &'a Path, text: &'a str) -> Self {
        let lines = text
            .lines()
            .enumerate()
            .map(|(k, l)| (k + 1, l.split('#').next().unwrap_or("").trim()))
            .filter(|(_, l)| !l.is_empty())
            .collect();
        Self { path, lines, at: 0 }
    }

    fn line_number(&self) -> usize {
        self.lines.get(self.at).or(self.lines.last()).map_or(0, |l| l.0)
    }

    fn next(&mut self, what: &str) -> Result<(usize, &'a str), SpectralError> {
        let l = self
            .lines
            .get(self.at)
            .copied()
            .ok_or_else(|| err(self.path, self.line_number(), format!("the file ends before {what}")))?;
        self.at += 1;
        Ok(l)
    }

    fn peek(&self) -> Option<&'a str> {
        self.lines.get(self.at).map(|l| l.1)
    }

    fn expect(&mut self, keyword: &str) -> Result<(), SpectralError> {
        let (n, l) = self.next(keyword)?;
        if l != keyword {
            return Err(err(self.path, n, format!("expected {keyword:?}, found {l:?}")));
        }
        Ok(())
    }

    /// A count of items that follow one per line, checked against the limit and the lines
    /// left ([`crate::limits::declared_count`]) before anything is allocated from it.
    fn count(&mut self, what: &str) -> Result<usize, SpectralError> {
        let n: u64 = self.number(what)?;
        let remaining = self.lines.len().saturating_sub(self.at);
        crate::limits::declared_count(what, n, remaining, 1)
            .map_err(|e| err(self.path, self.line_number(), e))
    }

    fn number<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, SpectralError> {
        let (n, l) = self.next(what)?;
        l.parse().map_err(|_| err(self.path, n, format!("{what}: {l:?} is not a number")))
    }

    /// `Key: value`.
    fn keyed(&mut self, key: &str) -> Result<(usize, &'a str), SpectralError> {
        let (n, l) = self.next(key)?;
        let v = l
            .strip_prefix(key)
            .and_then(|r| r.strip_prefix(':'))
            .ok_or_else(|| err(self.path, n, format!("expected \"{key}: …\", found {l:?}")))?;
        Ok((n, v.trim()))
    }
}

/// Parses a collection name: `H1_2D_P3`, `H1Pos_3D_P2`, `H1@P_2D_P2`, `L2_2D_P1`,
/// `L2_T1_3D_P4`, ….
pub fn parse_collection(name: &str) -> Option<Collection> {
    let (family, rest) = name.split_once('_')?;
    let (continuous, mut set) = match family {
        "H1" => (true, NodeSet::GaussLobatto),
        "H1Pos" => (true, NodeSet::Bernstein),
        f if f.starts_with("H1@") => (true, basis_char(f[3..].chars().next()?)?),
        "L2" => (false, NodeSet::Gauss),
        _ => return None,
    };
    let mut parts: Vec<&str> = rest.split('_').collect();
    if !continuous && parts.first().is_some_and(|p| p.starts_with('T')) {
        set = basis_id(parts[0][1..].parse().ok()?)?;
        parts.remove(0);
    }
    let [d, p] = parts[..] else { return None };
    let dim = d.strip_suffix('D')?.parse().ok()?;
    let order = p.strip_prefix('P')?.parse().ok()?;
    Some(Collection { continuous, dim, order, set, name: name.to_string() })
}

/// MFEM's `BasisType` ids (the `T<id>` of L2 names).
fn basis_id(id: u32) -> Option<NodeSet> {
    match id {
        0 => Some(NodeSet::Gauss),
        1 => Some(NodeSet::GaussLobatto),
        2 => Some(NodeSet::Bernstein),
        4 => Some(NodeSet::Equispaced),
        _ => None,
    }
}

/// MFEM's `BasisType` characters (the `@<c>` of H1 names).
fn basis_char(c: char) -> Option<NodeSet> {
    match c {
        'g' => Some(NodeSet::Gauss),
        'G' => Some(NodeSet::GaussLobatto),
        'P' => Some(NodeSet::Bernstein),
        'U' => Some(NodeSet::Equispaced),
        _ => None,
    }
}

fn read_space(lines: &mut Lines<'_>) -> Result<Space, SpectralError> {
    lines.expect("FiniteElementSpace")?;
    let (n, name) = lines.keyed("FiniteElementCollection")?;
    let collection = parse_collection(name).ok_or_else(|| {
        err(lines.path, n, format!("collection {name:?} is not an H1 or L2 collection this reader knows (H1_, H1Pos_, H1@<G|g|P|U>_, L2_, L2_T<0|1|2|4>_)"))
    })?;
    if !(1..=super::basis::MAX_ORDER).contains(&collection.order) {
        return Err(err(
            lines.path,
            n,
            format!("order {} is outside 1..={}", collection.order, super::basis::MAX_ORDER),
        ));
    }
    let (n, vdim) = lines.keyed("VDim")?;
    let vdim = vdim.parse().map_err(|_| err(lines.path, n, format!("VDim {vdim:?} is not a number")))?;
    let (n, ordering) = lines.keyed("Ordering")?;
    let by_vdim = match ordering {
        "0" => false,
        "1" => true,
        o => return Err(err(lines.path, n, format!("Ordering {o:?} is neither 0 nor 1"))),
    };
    Ok(Space { collection, vdim, by_vdim })
}

fn read_values(lines: &mut Lines<'_>, stop_at_keyword: bool) -> Result<Vec<f64>, SpectralError> {
    let mut values = Vec::new();
    while let Some(l) = lines.peek() {
        if stop_at_keyword
            && l.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
            && l.parse::<f64>().is_err()
        {
            break;
        }
        let (n, l) = lines.next("values")?;
        for w in l.split_whitespace() {
            let v: f64 = w.parse().map_err(|_| err(lines.path, n, format!("{w:?} is not a number")))?;
            if !v.is_finite() {
                return Err(err(lines.path, n, format!("{w:?} is not finite")));
            }
            values.push(v);
        }
    }
    Ok(values)
}

fn read_mesh_lines(path: &Path, lines: &mut Lines<'_>) -> Result<MfemMesh, SpectralError> {
    let (n, header) = lines.next("the header")?;
    if !header.starts_with("MFEM mesh v1.") {
        return Err(err(path, n, format!("expected \"MFEM mesh v1.0\", found {header:?}")));
    }
    lines.expect("dimension")?;
    let dim: u32 = lines.number("dimension")?;
    if dim != 2 && dim != 3 {
        return Err(err(
            path,
            lines.line_number(),
            format!("dimension {dim}: meshes of dimension 2 (quadrilaterals, triangles) and 3 (hexahedra, tetrahedra) only"),
        ));
    }
    lines.expect("elements")?;
    let count = lines.count("the element count")?;
    let corners_of = |g: u32| match (dim, g) {
        (2, GEOMETRY_SQUARE) => Some(4),
        (2, GEOMETRY_TRIANGLE) => Some(3),
        (3, GEOMETRY_CUBE) => Some(8),
        (3, GEOMETRY_TETRAHEDRON) => Some(4),
        _ => None,
    };
    let mut geometry = None;
    let at = lines.line_number();
    let mut elements = crate::limits::vec_for(count, "the elements").map_err(|e| err(path, at, e))?;
    for e in 0..count {
        let (n, l) = lines.next("an element")?;
        let w: Vec<usize> = l
            .split_whitespace()
            .map(|t| {
                t.parse()
                    .map_err(|_| err(path, n, format!("element {e}: {t:?} is not a non-negative integer")))
            })
            .collect::<Result<_, _>>()?;
        let g = w.get(1).map_or(u32::MAX, |&g| u32::try_from(g).unwrap_or(u32::MAX));
        let want = if dim == 2 {
            "geometry 3 (square) with 4 or 2 (triangle) with 3"
        } else {
            "geometry 5 (cube) with 8 or 4 (tetrahedron) with 4"
        };
        let corners = match corners_of(g) {
            Some(c) if w.len() == 2 + c => c,
            _ => {
                return Err(err(
                    path,
                    n,
                    format!(
                        "element {e}: geometry {} with {} vertices (a {dim}D mesh needs {want})",
                        w.get(1).copied().unwrap_or(0),
                        w.len().saturating_sub(2)
                    ),
                ))
            }
        };
        match geometry {
            Some(first) if first != g => {
                return Err(err(
                    path,
                    n,
                    format!("element {e}: geometry {g} differs from element 0's ({first}); one element geometry per mesh"),
                ))
            }
            _ => geometry = Some(g),
        }
        let vertices = &w[2..];
        if let Some(k) = (1..corners).find(|&k| vertices[..k].contains(&vertices[k])) {
            return Err(err(
                path,
                n,
                format!("element {e}: vertex {} appears twice (a degenerate element)", vertices[k]),
            ));
        }
        elements.push(vertices.to_vec());
    }
    // Skip the boundary.
    if lines.peek() == Some("boundary") {
        lines.next("boundary")?;
        let b = lines.count("the boundary count")?;
        for _ in 0..b {
            lines.next("a boundary element")?;
        }
    }
    lines.expect("vertices")?;
    let vertex_count: u64 = lines.number("the vertex count")?;
    // With a `nodes` section no vertex lines follow: only the absolute limit applies here;
    // otherwise the count is checked against the lines left below.
    let vertex_count = crate::limits::declared_count("the vertex count", vertex_count, usize::MAX, 1)
        .map_err(|e| err(path, lines.line_number(), e))?;
    for (e, el) in elements.iter().enumerate() {
        if let Some(&v) = el.iter().find(|&&v| v >= vertex_count) {
            return Err(SpectralError::File {
                path: path.to_path_buf(),
                detail: format!("element {e}: vertex {v} is out of range ({vertex_count} vertices)"),
            });
        }
    }
    let mut vertices = Vec::new();
    let mut nodes = None;
    if lines.peek() == Some("nodes") {
        lines.next("nodes")?;
        let space = read_space(lines)?;
        let values = read_values(lines, true)?;
        nodes = Some(GridFunction { path: path.to_path_buf(), space, values });
    } else {
        let sdim: usize = lines.number("the space dimension")?;
        if !(1..=3).contains(&sdim) {
            return Err(err(path, lines.line_number(), format!("space dimension {sdim}")));
        }
        let remaining = lines.lines.len().saturating_sub(lines.at);
        crate::limits::declared_count("the vertex count", vertex_count as u64, remaining, 1)
            .map_err(|e| err(path, lines.line_number(), e))?;
        for v in 0..vertex_count {
            let (n, l) = lines.next("a vertex")?;
            let c: Vec<f64> = l
                .split_whitespace()
                .map(|t| {
                    t.parse::<f64>().map_err(|_| err(path, n, format!("vertex {v}: {t:?} is not a number")))
                })
                .collect::<Result<_, _>>()?;
            if c.len() != sdim || c.iter().any(|x| !x.is_finite()) {
                return Err(err(path, n, format!("vertex {v}: {} finite coordinates expected", sdim)));
            }
            vertices.push(std::array::from_fn(|k| c.get(k).copied().unwrap_or(0.0)));
        }
    }
    let geometry = geometry.unwrap_or(if dim == 2 { GEOMETRY_SQUARE } else { GEOMETRY_CUBE });
    Ok(MfemMesh { path: path.to_path_buf(), dim, geometry, elements, vertices, vertex_count, nodes })
}

/// Reads an MFEM mesh file.
pub fn read_mesh(path: &Path) -> Result<MfemMesh, SpectralError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SpectralError::File { path: path.to_path_buf(), detail: e.to_string() })?;
    let mut lines = Lines::new(path, &text);
    read_mesh_lines(path, &mut lines)
}

/// Reads a GridFunction file.
pub fn read_grid_function(path: &Path) -> Result<GridFunction, SpectralError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SpectralError::File { path: path.to_path_buf(), detail: e.to_string() })?;
    let mut lines = Lines::new(path, &text);
    let space = read_space(&mut lines)?;
    let values = read_values(&mut lines, false)?;
    Ok(GridFunction { path: path.to_path_buf(), space, values })
}

/// Reads a GLVis "solution" stream saved to a file: the keyword `solution`, a mesh, then a
/// GridFunction.
pub fn read_solution(path: &Path) -> Result<(MfemMesh, GridFunction), SpectralError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| SpectralError::File { path: path.to_path_buf(), detail: e.to_string() })?;
    let mut lines = Lines::new(path, &text);
    lines.expect("solution")?;
    let mesh = read_mesh_lines(path, &mut lines)?;
    let space = read_space(&mut lines)?;
    let values = read_values(&mut lines, false)?;
    Ok((mesh, GridFunction { path: path.to_path_buf(), space, values }))
}

/// The vertices of an MFEM quadrilateral (counter-clockwise from (0, 0)) or hexahedron (bottom
/// face counter-clockwise, then the top) in lexicographic order (ξ fastest).
fn corners_lexicographic(element: &[usize]) -> Vec<usize> {
    let q = |v: &[usize]| [v[0], v[1], v[3], v[2]];
    let mut out = q(&element[..4]).to_vec();
    if element.len() == 8 {
        out.extend(q(&element[4..8]));
    }
    out
}

/// Refuses a `nodes` GridFunction unless it has 2 or 3 components for each of `dofs` DOFs;
/// the components otherwise.
pub(super) fn check_nodes(nodes: &GridFunction, dofs: usize) -> Result<usize, SpectralError> {
    let sdim = nodes.space.vdim;
    if !(2..=3).contains(&sdim) || nodes.values.len() != dofs * sdim {
        return Err(SpectralError::File {
            path: nodes.path.clone(),
            detail: format!(
                "nodes: {} values for {dofs} DOFs × VDim {sdim} of {}",
                nodes.values.len(),
                nodes.space.collection.name
            ),
        });
    }
    Ok(sdim)
}

/// Refuses step `k` of field `name` unless it is scalar (VDim 1) with `dofs` values, naming
/// its file.
pub(super) fn check_scalar_step(
    gf: &GridFunction,
    name: &str,
    k: usize,
    dofs: usize,
) -> Result<(), SpectralError> {
    let file = |detail: String| SpectralError::File { path: gf.path.clone(), detail };
    if gf.space.vdim != 1 {
        return Err(file(format!("field {name:?} step {k}: VDim {} (scalar fields only)", gf.space.vdim)));
    }
    if gf.values.len() != dofs {
        return Err(file(format!(
            "field {name:?} step {k}: {} values for {dofs} DOFs of {}",
            gf.values.len(),
            gf.space.collection.name
        )));
    }
    Ok(())
}

impl MfemMesh {
    /// Whether its elements are triangles or tetrahedra.
    pub fn is_simplex(&self) -> bool {
        matches!(self.geometry, GEOMETRY_TRIANGLE | GEOMETRY_TETRAHEDRON)
    }
}

/// The values of `gf`'s component `c` at global DOF `dof`.
pub(super) fn component(gf: &GridFunction, dofs: usize, dof: usize, c: usize) -> f64 {
    if gf.space.by_vdim {
        gf.values[dof * gf.space.vdim + c]
    } else {
        gf.values[c * dofs + dof]
    }
}

/// Builds the crate's mesh from an MFEM mesh and scalar GridFunctions on it (`fields`: a name
/// and one GridFunction per time step). Checks every count against the space it claims.
pub fn to_spectral(
    mesh: &MfemMesh,
    fields: &[(String, Vec<GridFunction>)],
) -> Result<SpectralMesh, SpectralError> {
    if mesh.is_simplex() {
        return super::mfem_simplex::to_spectral(mesh, fields);
    }
    let path = &mesh.path;
    let file = |detail: String| SpectralError::File { path: path.clone(), detail };
    let shape = if mesh.dim == 2 { Shape::Quadrilateral } else { Shape::Hexahedron };
    let topology = super::mfem_topology::Topology::new(mesh);
    // Geometry.
    let (geometry, points) = match &mesh.nodes {
        None => {
            let basis = Basis1d::new(NodeSet::Equispaced, 1)?;
            let points = mesh
                .elements
                .iter()
                .flat_map(|el| corners_lexicographic(el).into_iter().map(|v| mesh.vertices[v]))
                .collect();
            (basis, points)
        }
        Some(nodes) => {
            let c = &nodes.space.collection;
            if c.dim != mesh.dim {
                return Err(file(format!(
                    "nodes: collection {} is {}D on a {}D mesh",
                    c.name, c.dim, mesh.dim
                )));
            }
            let dofs = topology.dof_count(c)?;
            let sdim = check_nodes(nodes, dofs)?;
            let per_element = (c.order + 1).pow(mesh.dim);
            let mut points =
                crate::limits::vec_for(mesh.elements.len() * per_element, "the geometry's nodes")
                    .map_err(file)?;
            for e in 0..mesh.elements.len() {
                for d in topology.element_dofs(c, e) {
                    points.push(std::array::from_fn(|k| {
                        if k < sdim {
                            component(nodes, dofs, d, k)
                        } else {
                            0.0
                        }
                    }));
                }
            }
            (Basis1d::new(c.set, c.order)?, points)
        }
    };
    // Fields: all steps on one collection.
    let mut out_fields = Vec::new();
    let mut basis: Option<Basis1d> = None;
    for (name, steps) in fields {
        let mut values = Vec::new();
        for (k, gf) in steps.iter().enumerate() {
            let file = |detail: String| SpectralError::File { path: gf.path.clone(), detail };
            let c = &gf.space.collection;
            if c.dim != mesh.dim {
                return Err(file(format!(
                    "field {name:?}: collection {} is {}D on a {}D mesh",
                    c.name, c.dim, mesh.dim
                )));
            }
            let b = Basis1d::new(c.set, c.order)?;
            match &basis {
                Some(prev) if prev.set != b.set || prev.order != b.order => {
                    return Err(file(format!(
                    "field {name:?}: collection {} differs from the first field's (one basis per data set)",
                    c.name
                )))
                }
                _ => basis = Some(b),
            }
            let dofs = topology.dof_count(c)?;
            check_scalar_step(gf, name, k, dofs)?;
            let per_element = (c.order + 1).pow(mesh.dim);
            let mut v = crate::limits::vec_for(mesh.elements.len() * per_element, "the field's values")
                .map_err(file)?;
            for e in 0..mesh.elements.len() {
                v.extend(topology.element_dofs(c, e).into_iter().map(|d| gf.values[d]));
            }
            values.push(v);
        }
        out_fields.push(Field {
            name: name.clone(),
            times: (0..values.len()).map(|k| k as f64).collect(),
            steps: values,
        });
    }
    let basis = basis.ok_or_else(|| file("no fields".into()))?;
    SpectralMesh::new(shape, geometry, basis, points, out_fields).map_err(|e| file(e.to_string()))
}
