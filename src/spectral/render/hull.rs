//! Tighter bounds than an element's box for the rays of the isosurface and volume passes: per
//! solid element, [`HULL_PLANES`] half-spaces n · x ≤ h whose intersection contains it — one per
//! face of the straight element through its corners (a tetrahedron's 4, a hexahedron's 6; n the
//! face's outward normal), h the largest n · b over its Bernstein control points b (whose convex
//! hull contains the curved element, rational ones too). A ray is sampled only where it lies in
//! every half-space and the box (`spectral_ray_hull`, spectral_ray.glsl), instead of across the
//! whole box: most of a tetrahedron's box lies outside it, and a ray missing the hull costs
//! nothing.

use super::*;
use crate::spectral::Shape;

/// Half-spaces per element (a hexahedron's faces; a tetrahedron's 4 and two that hold
/// everything).
pub const HULL_PLANES: usize = 6;

/// A plane that every point satisfies (0 · x ≤ 1): the padding of a tetrahedron's list.
const EVERYWHERE: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

/// Corners of the reference tetrahedron and the faces opposite each (outward away from it).
const TET_CORNERS: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// Per element of a solid mesh, [`HULL_PLANES`] planes (n, h) with n · x ≤ h on the whole
/// element (see the module's documentation): h grown by 8 f32 ulps of the element's size so
/// the f32 test keeps its boundary.
pub fn element_hull_planes(mesh: &SpectralMesh) -> Result<Vec<[f32; 4]>> {
    let control = proxy::bernstein_hull(mesh)?;
    let per = mesh.points_per_element();
    let mut out = Vec::with_capacity(HULL_PLANES * mesh.elements());
    for e in 0..mesh.elements() {
        let points: Vec<glam::DVec3> = control[e * per..(e + 1) * per]
            .iter()
            .map(|p| glam::DVec3::new(p[0].into(), p[1].into(), p[2].into()))
            .collect();
        let size = points.iter().fold(0.0f64, |a, p| a.max(p.abs().max_element()));
        let slack = 8.0 * f64::from(f32::EPSILON) * size.max(f64::from(f32::MIN_POSITIVE));
        let corner = |r: [f64; 3]| glam::DVec3::from(mesh.map_hex(e, r).0);
        // (a point on the face side, the face's normal before orienting, a point inside).
        let faces: Vec<(glam::DVec3, glam::DVec3, glam::DVec3)> = if mesh.shape == Shape::Tetrahedron {
            let v = TET_CORNERS.map(corner);
            (0..4)
                .map(|k| {
                    let [a, b, c] = [(k + 1) % 4, (k + 2) % 4, (k + 3) % 4].map(|i| v[i]);
                    (a, (b - a).cross(c - a), v[k])
                })
                .collect()
        } else {
            let v: [glam::DVec3; 8] =
                std::array::from_fn(|k| corner([(k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2 & 1) as f64]));
            let centre = v.iter().copied().sum::<glam::DVec3>() / 8.0;
            super::iso::BOX_FACES
                .iter()
                .map(|f| (v[f[0]], (v[f[2]] - v[f[0]]).cross(v[f[3]] - v[f[1]]), centre))
                .collect()
        };
        for k in 0..HULL_PLANES {
            let Some(&(on, normal, inside)) = faces.get(k) else {
                out.push(EVERYWHERE);
                continue;
            };
            let mut n = normal.normalize_or_zero();
            if n == glam::DVec3::ZERO {
                out.push(EVERYWHERE);
                continue;
            }
            if n.dot(on - inside) < 0.0 {
                n = -n;
            }
            let h = points.iter().fold(f64::NEG_INFINITY, |a, p| a.max(n.dot(*p)));
            out.push([n.x as f32, n.y as f32, n.z as f32, (h + slack) as f32]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::basis::Basis1d;
    use crate::spectral::{generate, Field, NodeSet};

    /// The unit cube cut into six straight tetrahedra along its diagonal (order 1), each
    /// positively oriented.
    fn kuhn_cube() -> SpectralMesh {
        let mut points = Vec::new();
        for p in [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]] {
            let mut v = [[0.0f64; 3]; 4];
            for k in 0..3 {
                v[k + 1] = v[k];
                v[k + 1][p[k]] = 1.0;
            }
            let d = |a: usize| glam::DVec3::from(v[a]) - glam::DVec3::from(v[0]);
            if d(1).cross(d(2)).dot(d(3)) < 0.0 {
                v.swap(1, 2);
            }
            points.extend(v);
        }
        let values = points.iter().map(|p| p[0]).collect();
        let field = Field { name: "x".into(), times: vec![0.0], steps: vec![values] };
        let linear = Basis1d::new(NodeSet::Equispaced, 1).unwrap();
        SpectralMesh::new(Shape::Tetrahedron, linear.clone(), linear, points, vec![field]).unwrap()
    }

    /// Every point of every element (a 9³ grid of reference points, and its tetrahedral part)
    /// lies in each of its half-spaces; and the hull is tighter than the box: for a straight
    /// tetrahedron's planes, the box's far corner lies outside.
    #[test]
    fn hull_planes_hold_the_curved_elements() {
        let hexes = generate::hex_shell(2, 2, 2, 3, 3, NodeSet::GaussLobatto).unwrap();
        let planes = element_hull_planes(&hexes).unwrap();
        assert_eq!(planes.len(), HULL_PLANES * hexes.elements());
        let grid = |k: usize| k as f64 / 8.0;
        for e in 0..hexes.elements() {
            for (i, j, k) in (0..9).flat_map(|i| (0..9).flat_map(move |j| (0..9).map(move |k| (i, j, k)))) {
                let x = glam::DVec3::from(hexes.map_hex(e, [grid(i), grid(j), grid(k)]).0);
                for p in &planes[HULL_PLANES * e..HULL_PLANES * (e + 1)] {
                    let n = glam::DVec3::new(p[0].into(), p[1].into(), p[2].into());
                    assert!(n.dot(x) <= f64::from(p[3]) + 1e-9, "element {e}: {x} outside {p:?}");
                }
            }
        }
        // Six straight tetrahedra of a unit cube (Kuhn): each one's planes cut the cube.
        let tets = kuhn_cube();
        let planes = element_hull_planes(&tets).unwrap();
        for e in 0..tets.elements() {
            let own = &planes[HULL_PLANES * e..HULL_PLANES * (e + 1)];
            assert_eq!(own[4], EVERYWHERE);
            let holds = |x: glam::DVec3| {
                own.iter().all(|p| {
                    glam::DVec3::new(p[0].into(), p[1].into(), p[2].into()).dot(x) <= f64::from(p[3])
                })
            };
            let inside = (0..8)
                .filter(|&k| {
                    holds(glam::DVec3::new((k & 1) as f64, (k >> 1 & 1) as f64, (k >> 2 & 1) as f64))
                })
                .count();
            assert_eq!(inside, 4, "element {e}: a tetrahedron holds 4 of the cube's corners");
            for r in [[0.2, 0.2, 0.2], [0.0, 0.5, 0.5], [0.1, 0.1, 0.7]] {
                assert!(holds(glam::DVec3::from(tets.map_hex(e, r).0)));
            }
        }
    }
}
