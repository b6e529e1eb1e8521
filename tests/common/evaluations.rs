//! A tool's own evaluation of a data set at reference points (written by
//! scripts/vtk-fixtures.py and scripts/mfem-fixtures.py), and our mesh's distance from it.

use galerkin::spectral::{Shape, SpectralMesh};

/// One evaluation: element, reference point, the tool's physical point and field value.
#[derive(serde::Deserialize)]
pub struct Record {
    /// The element.
    pub element: usize,
    /// The reference point (2 or 3 coordinates).
    #[serde(rename = "ref")]
    pub reference: Vec<f64>,
    /// The tool's physical point there.
    pub x: Vec<f64>,
    /// The tool's field value there.
    pub value: f64,
}

/// The largest differences (geometry, field) between `mesh`'s map and field `field` (step 0)
/// and the tool's `records`.
pub fn worst_differences(mesh: &SpectralMesh, field: usize, records: &[Record]) -> (f64, f64) {
    let (mut worst_x, mut worst_u) = (0.0f64, 0.0f64);
    for r in records {
        let (x, u) = match mesh.shape {
            Shape::Quadrilateral | Shape::Triangle => {
                let (x, _) = mesh.map(r.element, r.reference[0], r.reference[1]);
                (x, mesh.value(field, 0, r.element, r.reference[0], r.reference[1]))
            }
            Shape::Hexahedron | Shape::Tetrahedron => {
                let at = [r.reference[0], r.reference[1], r.reference[2]];
                (mesh.map_hex(r.element, at).0, mesh.value_hex(field, 0, r.element, at))
            }
        };
        for (k, xk) in r.x.iter().enumerate() {
            worst_x = worst_x.max((x[k] - xk).abs());
        }
        worst_u = worst_u.max((u - r.value).abs());
    }
    (worst_x, worst_u)
}
