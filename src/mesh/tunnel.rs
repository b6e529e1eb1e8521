//! The 2D periodic tunnel with a triangular obstacle of seed 000 §7.1, meshed by constrained
//! Delaunay triangulation with refinement (the `spade` crate): the domain is
//! `[0, length] × [0, height]`, periodic in x (the left and right sides carry the same
//! vertices), with walls at y = 0 and y = height and an equilateral triangular obstacle
//! pointing upstream (−x) at `centre` with circumradius `radius`.
//!
//! The boundary is subdivided first (the sides identically, so they match) and kept
//! unsplit by the refinement, which bounds interior triangle areas by that of an equilateral
//! triangle of edge `cell` and their smallest angles by 25°.

use std::collections::HashSet;

use spade::{AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation};

use super::budget::CellBudget;
use super::{MeshError, SimplexMesh};

/// The tunnel's shape and resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct TunnelSpec {
    /// Length (the periodic axis x).
    pub length: f64,
    /// Height (walls at 0 and `height`).
    pub height: f64,
    /// Obstacle centre.
    pub centre: [f64; 2],
    /// Obstacle circumradius.
    pub radius: f64,
    /// Target edge length in the domain.
    pub cell: f64,
    /// Target edge length on the obstacle, as a fraction of `cell` (finer near the obstacle).
    pub obstacle_refinement: f64,
}

impl Default for TunnelSpec {
    fn default() -> Self {
        Self {
            length: 4.0,
            height: 1.0,
            centre: [1.0, 0.5],
            radius: 0.2,
            cell: 0.05,
            obstacle_refinement: 0.5,
        }
    }
}

/// A meshed tunnel: the mesh and which vertices lie on which part of the boundary.
#[derive(Clone, Debug)]
pub struct TunnelMesh {
    /// The triangulation.
    pub mesh: SimplexMesh,
    /// The spec it was meshed from.
    pub spec: TunnelSpec,
    /// Vertices on the obstacle.
    pub obstacle: Vec<u32>,
    /// Vertices on the walls and the periodic sides (fixed under obstacle deformation).
    pub outer: Vec<u32>,
}

/// Meshes the tunnel of `spec`; refused before meshing when the estimated triangle count
/// (the tunnel's area over the largest triangle's, plus the refinement along the obstacle) is
/// past `budget`.
pub fn tunnel(spec: &TunnelSpec, budget: &CellBudget) -> Result<TunnelMesh, MeshError> {
    let s = spec;
    let bad = |m: &str| Err(MeshError::Generation(format!("tunnel: {m}")));
    if ![s.length, s.height, s.radius, s.cell, s.obstacle_refinement]
        .iter()
        .all(|v| v.is_finite() && *v > 0.0)
    {
        return bad("length, height, radius, cell and obstacle_refinement must be positive and finite");
    }
    let corners = obstacle_corners(s.centre, s.radius);
    let margin = 0.5 * s.cell;
    if corners
        .iter()
        .any(|c| c[0] < margin || c[0] > s.length - margin || c[1] < margin || c[1] > s.height - margin)
    {
        return bad("the obstacle must lie inside the tunnel, half a cell away from its sides and walls");
    }
    if s.height / s.cell > 2000.0 || s.length / s.cell > 8000.0 {
        return bad("more than 2000 cells across the tunnel: raise `cell`");
    }
    if 3f64.sqrt() * s.radius / (s.cell * s.obstacle_refinement) > 100_000.0 {
        return bad("more than 100,000 points along an obstacle edge: raise `obstacle_refinement`");
    }
    let max_area = 3f64.sqrt() / 4.0 * s.cell * s.cell;
    let obstacle_points = 3.0 * 3f64.sqrt() * s.radius / (s.cell * s.obstacle_refinement);
    budget.check(
        &format!("tunnel at cell {}", s.cell),
        s.length * s.height / max_area + 20.0 * obstacle_points,
        "`cell`",
    )?;
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let insert = |cdt: &mut ConstrainedDelaunayTriangulation<Point2<f64>>, p: [f64; 2]| {
        cdt.insert(Point2::new(p[0], p[1])).map_err(|e| MeshError::Generation(format!("tunnel: {e:?}")))
    };
    // The outer rectangle, counter-clockwise, subdivided; the two sides identically.
    let nx = (s.length / s.cell).ceil() as usize;
    let ny = (s.height / s.cell).ceil() as usize;
    let mut outer_points = Vec::new();
    for i in 0..nx {
        outer_points.push([s.length * i as f64 / nx as f64, 0.0]);
    }
    for j in 0..ny {
        outer_points.push([s.length, s.height * j as f64 / ny as f64]);
    }
    for i in (1..=nx).rev() {
        outer_points.push([s.length * i as f64 / nx as f64, s.height]);
    }
    for j in (1..=ny).rev() {
        outer_points.push([0.0, s.height * j as f64 / ny as f64]);
    }
    let mut obstacle_points = Vec::new();
    let h_obstacle = s.cell * s.obstacle_refinement;
    for e in 0..3 {
        let (a, b) = (corners[e], corners[(e + 1) % 3]);
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let n = (len / h_obstacle).ceil().max(1.0) as usize;
        for i in 0..n {
            let t = i as f64 / n as f64;
            obstacle_points.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    for loop_points in [&outer_points, &obstacle_points] {
        let handles: Vec<_> = loop_points.iter().map(|&p| insert(&mut cdt, p)).collect::<Result<_, _>>()?;
        for i in 0..handles.len() {
            cdt.add_constraint(handles[i], handles[(i + 1) % handles.len()]);
        }
    }
    let result = cdt.refine(
        RefinementParameters::<f64>::new()
            .exclude_outer_faces(true)
            .keep_constraint_edges()
            .with_max_allowed_area(max_area)
            .with_angle_limit(AngleLimit::from_deg(25.0))
            .with_max_additional_vertices(4_000_000),
    );
    if !result.refinement_complete {
        return bad("the refinement did not complete (too many vertices)");
    }
    let excluded: HashSet<_> = result.excluded_faces.iter().copied().collect();
    let mut index = vec![u32::MAX; cdt.num_vertices()];
    let mut g = Vec::new();
    let mut cells = Vec::new();
    for face in cdt.inner_faces() {
        if excluded.contains(&face.fix()) {
            continue;
        }
        for v in face.vertices() {
            let slot = &mut index[v.fix().index()];
            if *slot == u32::MAX {
                *slot = (g.len() / 2) as u32;
                let p = v.position();
                g.push(p.x);
                g.push(p.y);
            }
            cells.push(*slot);
        }
    }
    let mesh = SimplexMesh::new(2, g, cells)?;
    let tol = 1e-9 * s.length.max(s.height);
    let mut obstacle = Vec::new();
    let mut outer = Vec::new();
    for v in 0..mesh.vertex_count() {
        let p = mesh.point(v);
        if p[0] <= tol || p[0] >= s.length - tol || p[1] <= tol || p[1] >= s.height - tol {
            outer.push(v as u32);
        } else if on_triangle(&corners, [p[0], p[1]], tol) {
            obstacle.push(v as u32);
        }
    }
    Ok(TunnelMesh { mesh, spec: spec.clone(), obstacle, outer })
}

/// The obstacle's corners: an equilateral triangle pointing upstream (−x).
pub fn obstacle_corners(centre: [f64; 2], radius: f64) -> [[f64; 2]; 3] {
    [180.0f64, 300.0, 60.0].map(|deg| {
        let a = deg.to_radians();
        [centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]
    })
}

fn on_triangle(c: &[[f64; 2]; 3], p: [f64; 2], tol: f64) -> bool {
    (0..3).any(|e| {
        let (a, b) = (c[e], c[(e + 1) % 3]);
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        let t = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (len * len);
        let dist = ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / len;
        dist <= 1e3 * tol && (-1e-9..=1.0 + 1e-9).contains(&t)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{FaceKind, Periodic, Topology};

    #[test]
    fn the_tunnel_covers_the_domain_minus_the_obstacle_and_wraps_in_x() {
        let spec = TunnelSpec { cell: 0.1, ..Default::default() };
        let t = tunnel(&spec, &CellBudget::machine()).expect("tunnel");
        let area: f64 = t.mesh.volumes().iter().sum();
        let obstacle_area = 3.0 * 3f64.sqrt() / 4.0 * spec.radius * spec.radius;
        assert!((area - (spec.length * spec.height - obstacle_area)).abs() < 1e-12, "area {area}");
        let topo = Topology::new(&t.mesh, Some(Periodic { axis: 0 })).expect("topology");
        let wraps = (0..topo.face_count()).filter(|&f| topo.kind(f) == FaceKind::Wrap).count();
        assert_eq!(wraps, (spec.height / spec.cell).ceil() as usize, "one wrap face per side segment");
        // Boundary = the two walls and the obstacle's three edges.
        let nx = (spec.length / spec.cell).ceil() as usize;
        let per_edge = (3f64.sqrt() * spec.radius / (spec.cell * spec.obstacle_refinement)).ceil() as usize;
        assert_eq!(topo.boundary_faces().len(), 2 * nx + 3 * per_edge);
        assert_eq!(t.obstacle.len(), 3 * per_edge);
        // Minimum angle: the refinement's 25° bound (boundary-adjacent triangles included).
        let mut min_angle = 180.0f64;
        for c in 0..t.mesh.cell_count() {
            let p = t.mesh.cell_points(c);
            for k in 0..3 {
                let (a, b, o) = (p[(k + 1) % 3], p[(k + 2) % 3], p[k]);
                let (u, v) = ([a[0] - o[0], a[1] - o[1]], [b[0] - o[0], b[1] - o[1]]);
                let cos = (u[0] * v[0] + u[1] * v[1])
                    / ((u[0] * u[0] + u[1] * u[1]) * (v[0] * v[0] + v[1] * v[1])).sqrt();
                min_angle = min_angle.min(cos.acos().to_degrees());
            }
        }
        assert!(min_angle > 20.0, "smallest angle {min_angle}°");
    }

    #[test]
    fn bad_tunnels_are_refused() {
        assert!(tunnel(&TunnelSpec { radius: 0.6, ..Default::default() }, &CellBudget::machine()).is_err());
        assert!(tunnel(&TunnelSpec { cell: -1.0, ..Default::default() }, &CellBudget::machine()).is_err());
        assert!(tunnel(&TunnelSpec { cell: f64::NAN, ..Default::default() }, &CellBudget::machine()).is_err());
    }
}
