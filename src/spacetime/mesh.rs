//! The spacetime mesh of seed 003 §4.1: vertices (x, y, t), tetrahedra as four vertex indices
//! (non-conforming allowed; each non-degenerate), and per element its local frame, material
//! and cubic displacement (§4.2.1). Elements are independent: the field is discontinuous
//! across faces.

use super::cubic::{CubicCoefficients, LocalFrame, Material};
use super::error::SpacetimeError;

/// One element's data besides its corners.
#[derive(Clone, Debug, PartialEq)]
pub struct ElementField {
    /// The local frame of its polynomial.
    pub frame: LocalFrame,
    /// Index into [`SpacetimeMesh::materials`].
    pub material: u32,
    /// The displacement's 20 coefficient 2-vectors.
    pub coefficients: CubicCoefficients,
}

/// A tetrahedral spacetime mesh with a cubic displacement per element.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpacetimeMesh {
    /// Vertices (x, y, t).
    pub vertices: Vec<[f64; 3]>,
    /// Tetrahedra: four vertex indices each.
    pub tets: Vec<[u32; 4]>,
    /// One per tetrahedron.
    pub fields: Vec<ElementField>,
    /// Materials referenced by the elements.
    pub materials: Vec<Material>,
}

/// Six times the signed volume of a spacetime tetrahedron.
pub fn six_volume(p: [[f64; 3]; 4]) -> f64 {
    let d = |i: usize| [p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]];
    let (a, b, c) = (d(1), d(2), d(3));
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

impl SpacetimeMesh {
    /// Corners of element `e`.
    pub fn corners(&self, e: usize) -> [[f64; 3]; 4] {
        self.tets[e].map(|i| self.vertices[i as usize])
    }

    /// Lowest time of element `e` (the sort key of §4.1).
    pub fn lowest_time(&self, e: usize) -> f64 {
        self.corners(e).iter().map(|p| p[2]).fold(f64::INFINITY, f64::min)
    }

    /// Highest time of element `e`.
    pub fn highest_time(&self, e: usize) -> f64 {
        self.corners(e).iter().map(|p| p[2]).fold(f64::NEG_INFINITY, f64::max)
    }

    /// The time span covered by the vertices.
    pub fn time_range(&self) -> (f64, f64) {
        self.vertices
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| (lo.min(p[2]), hi.max(p[2])))
    }

    /// The spatial bounding box `([x_lo, y_lo], [x_hi, y_hi])`.
    pub fn space_bounds(&self) -> ([f64; 2], [f64; 2]) {
        self.vertices.iter().fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
            ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
        })
    }

    /// Checks everything seed 003 §4.1 assumes and the renderer relies on: indices in range,
    /// finite values, non-degenerate tetrahedra (|6·volume| above 1e-12 of the element's
    /// bounding-box volume), positive frame extents, materials with μ > 0, λ + μ > 0 and
    /// positive density. The first problem found is returned, naming the element.
    pub fn validate(&self) -> Result<(), SpacetimeError> {
        if self.fields.len() != self.tets.len() {
            return Err(SpacetimeError::Length {
                what: "element fields".into(),
                found: self.fields.len(),
                expected: self.tets.len(),
            });
        }
        for (v, p) in self.vertices.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(SpacetimeError::NotFinite { element: v, what: format!("vertex {v}") });
            }
        }
        for (m, mat) in self.materials.iter().enumerate() {
            if let Some(what) = mat.problem() {
                return Err(SpacetimeError::Invalid { element: m, what: format!("material {m} {what}") });
            }
        }
        for (e, tet) in self.tets.iter().enumerate() {
            for &i in tet {
                if i as usize >= self.vertices.len() {
                    return Err(SpacetimeError::BadIndex {
                        element: e,
                        index: u64::from(i),
                        vertices: self.vertices.len(),
                    });
                }
            }
            let p = self.corners(e);
            let frame = LocalFrame::bounding(&p);
            let scale = frame.extent.iter().product::<f64>();
            let volume = six_volume(p) / 6.0;
            if volume.abs() <= 1e-12 * scale {
                return Err(SpacetimeError::Degenerate { element: e, volume });
            }
            let f = &self.fields[e];
            if f.frame.centre.iter().chain(&f.frame.extent).any(|x| !x.is_finite()) {
                return Err(SpacetimeError::NotFinite { element: e, what: "the local frame".into() });
            }
            if f.frame.extent.iter().any(|&w| w <= 0.0) {
                return Err(SpacetimeError::Invalid {
                    element: e,
                    what: format!("frame extents must be positive, got {:?}", f.frame.extent),
                });
            }
            if f.coefficients.iter().flatten().any(|x| !x.is_finite()) {
                return Err(SpacetimeError::NotFinite {
                    element: e,
                    what: "a displacement coefficient".into(),
                });
            }
            if f.material as usize >= self.materials.len() {
                return Err(SpacetimeError::Invalid {
                    element: e,
                    what: format!(
                        "material {} does not exist ({} materials)",
                        f.material,
                        self.materials.len()
                    ),
                });
            }
        }
        Ok(())
    }

    /// Reorders the elements by lowest time (§4.1), so that the elements a time plane can cut
    /// form a contiguous range ([`super::SpacetimeData::active_range`]).
    pub fn sort_by_lowest_time(&mut self) {
        let mut order: Vec<usize> = (0..self.tets.len()).collect();
        let keys = self.lowest_times();
        order.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]).then(a.cmp(&b)));
        self.tets = order.iter().map(|&e| self.tets[e]).collect();
        self.fields = order.iter().map(|&e| self.fields[e].clone()).collect();
    }

    /// Longest time span of one element.
    pub fn longest_duration(&self) -> f64 {
        (0..self.tets.len()).map(|e| self.highest_time(e) - self.lowest_time(e)).fold(0.0, f64::max)
    }

    /// Every element's lowest time, in element order.
    pub fn lowest_times(&self) -> Vec<f64> {
        (0..self.tets.len()).map(|e| self.lowest_time(e)).collect()
    }
}
