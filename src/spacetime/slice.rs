//! Slicing a spacetime mesh with the plane `t = const` (seed 003 §4.1): each active
//! tetrahedron is cut into a triangle or a quadrilateral carrying its element index.
//!
//! This is the CPU f64 reference of `shaders-glsl/spacetime/slice.comp`, which does the same in
//! a compute pass. A vertex counts as *below* the plane when `t_i < t` and as *above* otherwise,
//! so a plane through a vertex, an edge or a face is a consistent limit of a plane just above
//! it: a face lying in the plane is produced once (by the element below it), and cut points
//! on edges that end in the plane are that vertex exactly. On a conforming mesh the polygons
//! therefore tile the domain at every `t`.

use super::mesh::SpacetimeMesh;

/// One cut: a triangle or a convex quadrilateral (corners in cyclic order) of one element.
#[derive(Clone, Debug, PartialEq)]
pub struct SlicePolygon {
    /// The element cut.
    pub element: u32,
    /// Its corners (x, y): three or four.
    pub corners: Vec<[f64; 2]>,
}

impl SlicePolygon {
    /// Area (shoelace), non-negative.
    pub fn area(&self) -> f64 {
        let c = &self.corners;
        let mut a = 0.0;
        for i in 0..c.len() {
            let (p, q) = (c[i], c[(i + 1) % c.len()]);
            a += p[0] * q[1] - q[0] * p[1];
        }
        0.5 * a.abs()
    }

    /// The fan triangulation the renderer draws: (0, 1, 2) and, for a quadrilateral, (0, 2, 3).
    pub fn triangles(&self) -> Vec<[[f64; 2]; 3]> {
        let c = &self.corners;
        (1..c.len() - 1).map(|i| [c[0], c[i], c[i + 1]]).collect()
    }
}

/// The point where the edge from `below` (t < plane) to `above` (t ≥ plane) meets the plane.
fn cut(below: [f64; 3], above: [f64; 3], t: f64) -> [f64; 2] {
    let s = (t - below[2]) / (above[2] - below[2]);
    [below[0] + s * (above[0] - below[0]), below[1] + s * (above[1] - below[1])]
}

/// The cut of one tetrahedron by the plane `t`, if the plane separates its corners.
pub fn slice_tet(p: [[f64; 3]; 4], t: f64) -> Option<Vec<[f64; 2]>> {
    let below: Vec<usize> = (0..4).filter(|&i| p[i][2] < t).collect();
    let above: Vec<usize> = (0..4).filter(|&i| p[i][2] >= t).collect();
    match (below.as_slice(), above.as_slice()) {
        (&[b], others) => Some(others.iter().map(|&a| cut(p[b], p[a], t)).collect()),
        (others, &[a]) => Some(others.iter().map(|&b| cut(p[b], p[a], t)).collect()),
        (&[a, b], &[c, d]) => {
            Some(vec![cut(p[a], p[c], t), cut(p[a], p[d], t), cut(p[b], p[d], t), cut(p[b], p[c], t)])
        }
        _ => None,
    }
}

/// Every polygon of the slice at `t`, in element order.
pub fn slice(mesh: &SpacetimeMesh, t: f64) -> Vec<SlicePolygon> {
    (0..mesh.tets.len())
        .filter_map(|e| {
            slice_tet(mesh.corners(e), t).map(|corners| SlicePolygon { element: e as u32, corners })
        })
        .collect()
}

/// Quadrisection level of a triangle of area `area` under the threshold `max_area`: the
/// smallest `L ≤ max_level` with `area / 4^L ≤ max_area` (seed 003 §4.2.2's subdivision by an
/// area threshold). `L` levels of recursive quadrisection give `4^L` triangles, the
/// barycentric grid of [`subdivide`].
pub fn subdivision_level(area: f64, max_area: f64, max_level: u32) -> u32 {
    let mut level = 0;
    let mut a = area;
    while a > max_area && level < max_level {
        a /= 4.0;
        level += 1;
    }
    level
}

/// The `4^level` triangles of `level` recursive quadrisections of `tri`.
pub fn subdivide(tri: [[f64; 2]; 3], level: u32) -> Vec<[[f64; 2]; 3]> {
    let n = 1u32 << level;
    let at = |i: u32, j: u32| {
        let (a, b) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
        let c = 1.0 - a - b;
        [c * tri[0][0] + a * tri[1][0] + b * tri[2][0], c * tri[0][1] + a * tri[1][1] + b * tri[2][1]]
    };
    let mut out = Vec::with_capacity((n * n) as usize);
    for i in 0..n {
        for j in 0..n - i {
            out.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
            if j + 1 < n - i {
                out.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cuts_through_vertices_edges_and_faces() {
        let tet = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        // Through the bottom face: the face belongs to the element above it, not to this one.
        assert_eq!(slice_tet(tet, 0.0), None);
        // Just above it: the bottom face, shrunk.
        let c = slice_tet(tet, 0.25).unwrap();
        assert_eq!(c.len(), 3);
        // Through the apex: a point (the three cuts coincide): zero area, not dropped.
        let c = slice_tet(tet, 1.0).unwrap();
        assert!(c.iter().all(|p| *p == [0.0, 0.0]));
        // Through an edge: corners 0, 1 at t = 0.5, corner 2 below, 3 above: the edge and the
        // midpoint of edge 2–3.
        let tet = [[0.0, 0.0, 0.5], [1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [0.3, 0.5, 1.0]];
        let c = slice_tet(tet, 0.5).unwrap();
        assert_eq!(c, vec![[0.0, 0.0], [1.0, 0.0], [0.15, 0.75]]);
        assert!((SlicePolygon { element: 0, corners: c }.area() - 0.375).abs() < 1e-15);
        // A quadrilateral: two corners on each side, in cyclic order.
        let tet = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]];
        let c = slice_tet(tet, 0.5).unwrap();
        assert_eq!(c, vec![[0.0, 0.5], [0.0, 0.0], [0.5, 0.0], [0.5, 0.5]]);
        assert!((SlicePolygon { element: 0, corners: c }.area() - 0.25).abs() < 1e-15);
    }

    #[test]
    fn subdivision_tiles_the_triangle() {
        let tri = [[0.0, 0.0], [2.0, 0.0], [0.0, 1.0]];
        for level in 0..4 {
            let parts = subdivide(tri, level);
            assert_eq!(parts.len(), 4usize.pow(level));
            let area: f64 =
                parts.iter().map(|t| SlicePolygon { element: 0, corners: t.to_vec() }.area()).sum();
            assert!((area - 1.0).abs() < 1e-14);
        }
        assert_eq!(subdivision_level(1.0, 0.3, 8), 1);
        assert_eq!(subdivision_level(1.0, 0.01, 2), 2);
        assert_eq!(subdivision_level(0.1, 0.3, 8), 0);
    }
}
