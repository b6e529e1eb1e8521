//! One spacetime element as the device and the `.gst` file hold it: a self-contained 240-byte
//! record (corners, local frame, material index, the 20 coefficient 2-vectors, all f32), so
//! that the elements a time plane can cut — a contiguous range once sorted by lowest time
//! (seed 003 §4.1) — are one contiguous byte range to stream from disk to the device.
//! `SpacetimeRecord` in `shaders-glsl/include/spacetime_cubic.glsl` is its GLSL twin.

use bytemuck::{Pod, Zeroable};

use super::cubic::{CubicCoefficients, LocalFrame, Material};
use super::mesh::{six_volume, SpacetimeMesh};

/// One element: corners `(x, y, t)`, frame, material and cubic displacement (f32).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ElementRecord {
    /// The four corners `(x, y, t)`, packed.
    pub corners: [f32; 12],
    /// Frame centre `c` (x, y, t).
    pub centre: [f32; 3],
    /// Index into the data set's materials.
    pub material: u32,
    /// Frame extents `w` (x, y, t).
    pub extent: [f32; 3],
    /// Zero (pads the record to 16-byte alignment).
    pub reserved: u32,
    /// The 20 displacement coefficient 2-vectors, in the order of [`super::MONOMIALS`].
    pub coefficients: [[f32; 2]; 20],
}

/// A material as the device reads it: `(λ, μ, ρ, 0)`.
pub fn gpu_material(m: &Material) -> [f32; 4] {
    [m.lambda as f32, m.mu as f32, m.density as f32, 0.0]
}

impl ElementRecord {
    /// Bytes per record (the std430 size of `SpacetimeRecord`).
    pub const BYTES: usize = 240;

    /// A record from f64 data (rounded to f32).
    pub fn new(corners: [[f64; 3]; 4], frame: &LocalFrame, material: u32, c: &CubicCoefficients) -> Self {
        Self {
            corners: std::array::from_fn(|k| corners[k / 3][k % 3] as f32),
            centre: frame.centre.map(|x| x as f32),
            material,
            extent: frame.extent.map(|x| x as f32),
            reserved: 0,
            coefficients: c.map(|v| v.map(|x| x as f32)),
        }
    }

    /// Element `e` of `mesh`.
    pub fn of(mesh: &SpacetimeMesh, e: usize) -> Self {
        let f = &mesh.fields[e];
        Self::new(mesh.corners(e), &f.frame, f.material, &f.coefficients)
    }

    /// The corners in f64.
    pub fn corner_points(&self) -> [[f64; 3]; 4] {
        std::array::from_fn(|i| std::array::from_fn(|k| f64::from(self.corners[3 * i + k])))
    }

    /// The lowest corner time (the sort key of §4.1).
    pub fn lowest_time(&self) -> f32 {
        [2, 5, 8, 11].map(|k| self.corners[k]).into_iter().fold(f32::INFINITY, f32::min)
    }

    /// The highest corner time.
    pub fn highest_time(&self) -> f32 {
        [2, 5, 8, 11].map(|k| self.corners[k]).into_iter().fold(f32::NEG_INFINITY, f32::max)
    }

    /// The local frame in f64.
    pub fn frame(&self) -> LocalFrame {
        LocalFrame { centre: self.centre.map(f64::from), extent: self.extent.map(f64::from) }
    }

    /// The coefficients in f64.
    pub fn coefficients_f64(&self) -> CubicCoefficients {
        self.coefficients.map(|v| v.map(f64::from))
    }

    /// What is wrong with this record, if anything, for a data set of `materials` materials:
    /// the checks of [`SpacetimeMesh::validate`] (finite values, positive extents, a material
    /// that exists, a non-degenerate tetrahedron).
    pub fn problem(&self, materials: usize) -> Option<String> {
        if self.corners.iter().any(|x| !x.is_finite()) {
            return Some("a corner is not finite".into());
        }
        if self.centre.iter().chain(&self.extent).any(|x| !x.is_finite()) {
            return Some("the local frame is not finite".into());
        }
        if self.extent.iter().any(|&w| w <= 0.0) {
            return Some(format!("frame extents must be positive, got {:?}", self.extent));
        }
        if self.coefficients.iter().flatten().any(|x| !x.is_finite()) {
            return Some("a displacement coefficient is not finite".into());
        }
        if self.material as usize >= materials {
            return Some(format!("material {} does not exist ({materials} materials)", self.material));
        }
        let p = self.corner_points();
        let scale: f64 = LocalFrame::bounding(&p).extent.iter().product();
        let volume = six_volume(p) / 6.0;
        if volume.abs() <= 1e-12 * scale || scale == 0.0 {
            return Some(format!("degenerate tetrahedron (spacetime volume {volume:e})"));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_is_the_std430_size_of_its_glsl_twin() {
        // 3 + 1 + 1 vec4 and 20 vec2: 80 + 160 bytes, 16-byte aligned.
        assert_eq!(std::mem::size_of::<ElementRecord>(), ElementRecord::BYTES);
        assert_eq!(ElementRecord::BYTES % 16, 0);
    }

    #[test]
    fn problems_are_found() {
        let frame = LocalFrame { centre: [0.5; 3], extent: [1.0; 3] };
        let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let good = ElementRecord::new(corners, &frame, 0, &[[0.0; 2]; 20]);
        assert_eq!(good.problem(1), None);
        assert!(good.problem(0).unwrap().contains("material 0 does not exist"));
        let mut flat = good;
        flat.corners[11] = 0.0;
        assert!(flat.problem(1).unwrap().contains("degenerate"));
        let mut nan = good;
        nan.coefficients[3][1] = f32::NAN;
        assert!(nan.problem(1).unwrap().contains("coefficient"));
        assert_eq!(good.lowest_time(), 0.0);
        assert_eq!(good.highest_time(), 1.0);
    }
}
