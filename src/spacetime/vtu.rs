//! VTK XML unstructured grids (`.vtu`) of spacetime data, for interoperability: points are
//! `(x, y, t)`, cells are `VTK_TETRA` (10), and cell data hold each element's field —
//! `coefficients` (40 components: the 2-vectors `c_α` of the cubic, x then y, in the monomial
//! order of [`super::MONOMIALS`]), `frame` (6: centre x, y, t, extents x, y, t), `material`
//! (Int32 index) and `lambda`, `mu`, `density` (the material's values per cell, so ParaView
//! users see them).
//!
//! The container (encodings, compression, atomic writing) is [`crate::vtk`]'s. Optional on reading: `frame` (default: each element's bounding box, the generator's
//! frame), `material` (default: one material per distinct (λ, μ, ρ)) and `density` (default 1).
//! Every error names the file and, for data errors, the array or element.

use std::collections::HashMap;
use std::path::Path;

use super::cubic::{LocalFrame, Material};
use super::error::SpacetimeError;
use super::mesh::{ElementField, SpacetimeMesh};
use crate::vtk::{self, OutArray, Values, VtkError};

/// `VTK_TETRA`.
const VTK_TETRA: u8 = 10;

fn err(path: &Path, detail: impl Into<String>) -> SpacetimeError {
    SpacetimeError::File { path: path.to_path_buf(), detail: detail.into() }
}

impl From<VtkError> for SpacetimeError {
    fn from(e: VtkError) -> Self {
        SpacetimeError::File { path: e.path, detail: e.detail }
    }
}

/// Writes `mesh` to `path` (whole or not at all, [`crate::atomic_file`]). A mesh the reader
/// would refuse (a NaN, a degenerate tetrahedron: [`SpacetimeMesh::validate`]) is refused here
/// too, naming the element, instead of being written.
pub fn write(path: &Path, mesh: &SpacetimeMesh) -> Result<(), SpacetimeError> {
    mesh.validate().map_err(|e| SpacetimeError::File {
        path: path.to_path_buf(),
        detail: format!("not written: {e}"),
    })?;
    let n_cells = mesh.tets.len();
    let fields = &mesh.fields;
    let f64s = |section, name: &str, components, v: Vec<f64>| OutArray {
        section,
        name: name.to_string(),
        components,
        values: Values::F64(v),
    };
    let mut arrays = vec![
        f64s("Points", "Points", 3, mesh.vertices.iter().flatten().copied().collect()),
        OutArray {
            section: "Cells",
            name: "connectivity".into(),
            components: 1,
            values: Values::I64(mesh.tets.iter().flatten().map(|&i| i64::from(i)).collect()),
        },
        OutArray {
            section: "Cells",
            name: "offsets".into(),
            components: 1,
            values: Values::I64((1..=n_cells as i64).map(|k| 4 * k).collect()),
        },
        OutArray {
            section: "Cells",
            name: "types".into(),
            components: 1,
            values: Values::U8(vec![VTK_TETRA; n_cells]),
        },
        f64s("CellData", "coefficients", 40, fields.iter().flat_map(|f| f.coefficients).flatten().collect()),
        f64s(
            "CellData",
            "frame",
            6,
            fields.iter().flat_map(|f| f.frame.centre.into_iter().chain(f.frame.extent)).collect(),
        ),
        OutArray {
            section: "CellData",
            name: "material".into(),
            components: 1,
            values: Values::I32(fields.iter().map(|f| f.material as i32).collect()),
        },
    ];
    let mat = |f: &ElementField| mesh.materials.get(f.material as usize).copied();
    for (name, get) in [
        ("lambda", (|m: Material| m.lambda) as fn(Material) -> f64),
        ("mu", |m: Material| m.mu),
        ("density", |m: Material| m.density),
    ] {
        arrays.push(f64s("CellData", name, 1, fields.iter().map(|f| mat(f).map_or(f64::NAN, get)).collect()));
    }
    vtk::write(
        path,
        "galerkin spacetime DG data (seed 003): points are (x, y, t); cell data hold each element's cubic displacement.",
        mesh.vertices.len(),
        n_cells,
        &arrays,
    )?;
    Ok(())
}

/// Reads a spacetime mesh from a `.vtu` file (see the module docs for what is accepted).
/// The mesh is validated; elements keep the file's order.
pub fn read(path: &Path) -> Result<SpacetimeMesh, SpacetimeError> {
    let grid = vtk::read(path)?;
    let (n_points, n_cells) = (grid.points, grid.cells);
    let need = |section: &str, name: &str, comps: usize, n: usize| grid.require(section, name, comps, n);
    let optional = |name: &str, comps: usize| grid.optional("CellData", name, comps, n_cells);
    let points = need("Points", "Points", 3, n_points)?;
    let conn = need("Cells", "connectivity", 1, 4 * n_cells)?;
    let offsets = need("Cells", "offsets", 1, n_cells)?;
    let types = need("Cells", "types", 1, n_cells)?;
    let coefficients = need("CellData", "coefficients", 40, n_cells)?;
    let lambda = need("CellData", "lambda", 1, n_cells)?;
    let mu = need("CellData", "mu", 1, n_cells)?;
    let density = optional("density", 1)?;
    let frame = optional("frame", 6)?;
    let material = optional("material", 1)?;

    let mut mesh = SpacetimeMesh {
        vertices: points.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect(),
        ..Default::default()
    };
    let mut materials: HashMap<u32, Material> = HashMap::new();
    let mut by_value: HashMap<[u64; 3], u32> = HashMap::new();
    for e in 0..n_cells {
        let cell = |d: String| err(path, format!("element {e}: {d}"));
        if types[e] != f64::from(VTK_TETRA) {
            return Err(cell(format!("cell type {} (only VTK_TETRA = 10 is a spacetime element)", types[e])));
        }
        if offsets[e] != (4 * (e + 1)) as f64 {
            return Err(cell(format!("offset {} (tetrahedra need 4 × (element + 1))", offsets[e])));
        }
        let mut tet = [0u32; 4];
        for (k, t) in tet.iter_mut().enumerate() {
            let i = conn[4 * e + k];
            if !(i >= 0.0 && i < n_points as f64 && i.fract() == 0.0) {
                return Err(cell(format!("vertex index {i} is out of range ({n_points} points)")));
            }
            *t = i as u32;
        }
        mesh.tets.push(tet);
        let m = Material { lambda: lambda[e], mu: mu[e], density: density.as_ref().map_or(1.0, |d| d[e]) };
        // Each element's own values, before materials are merged (a NaN in one element of a
        // material others define well would otherwise be dropped silently).
        if let Some(problem) = m.problem() {
            return Err(cell(format!("lambda, mu, density: {problem}")));
        }
        let index = match &material {
            Some(ids) => {
                let id = ids[e];
                if !(id >= 0.0 && id.fract() == 0.0 && id < 65536.0) {
                    return Err(cell(format!("material index {id} is not a small non-negative integer")));
                }
                let id = id as u32;
                let known = *materials.entry(id).or_insert(m);
                if known != m {
                    return Err(cell(format!("material {id} is {m:?} here but {known:?} elsewhere")));
                }
                id
            }
            None => {
                let key = [m.lambda.to_bits(), m.mu.to_bits(), m.density.to_bits()];
                let next = by_value.len() as u32;
                let id = *by_value.entry(key).or_insert(next);
                materials.insert(id, m);
                id
            }
        };
        let corners = tet.map(|i| mesh.vertices[i as usize]);
        let frame = match &frame {
            Some(f) => {
                let f = &f[6 * e..6 * e + 6];
                LocalFrame { centre: [f[0], f[1], f[2]], extent: [f[3], f[4], f[5]] }
            }
            None => LocalFrame::bounding(&corners),
        };
        let c = &coefficients[40 * e..40 * e + 40];
        mesh.fields.push(ElementField {
            frame,
            material: index,
            coefficients: std::array::from_fn(|a| [c[2 * a], c[2 * a + 1]]),
        });
    }
    let n_materials = materials.keys().max().map_or(0, |&m| m as usize + 1);
    mesh.materials = (0..n_materials)
        // An index no element uses gets a copy of one that is used (it is never read).
        .map(|i| {
            materials
                .get(&(i as u32))
                .or_else(|| materials.values().next())
                .copied()
                .expect("n_materials > 0")
        })
        .collect();
    mesh.validate().map_err(|e| err(path, e.to_string()))?;
    Ok(mesh)
}
