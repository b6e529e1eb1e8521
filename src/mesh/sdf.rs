//! Signed distance functions for isosurface stuffing ([`super::stuffing`]): negative inside,
//! positive outside, |∇| ≈ 1. Primitives (sphere, capsule, box), their union and difference
//! — the seed's cavity (§7.2: "we designed the cavity using simple level set primitives") —
//! and the signed distance to a closed OBJ surface ([`ObjSurface`]), so a domain can be a box
//! with a user's object cut out of it.

use super::MeshError;

/// A signed distance function.
pub trait Sdf: Send + Sync {
    /// Signed distance at `p` (negative inside).
    fn distance(&self, p: [f64; 3]) -> f64;
    /// A box containing the inside: `(lo, hi)`.
    fn bounds(&self) -> ([f64; 3], [f64; 3]);
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// A ball.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub centre: [f64; 3],
    /// Radius.
    pub radius: f64,
}

impl Sdf for Sphere {
    fn distance(&self, p: [f64; 3]) -> f64 {
        norm(sub(p, self.centre)) - self.radius
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.centre.map(|c| c - self.radius), self.centre.map(|c| c + self.radius))
    }
}

/// A capsule: the points within `radius` of the segment `a`–`b` (the cavity's tunnels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// One end of the axis.
    pub a: [f64; 3],
    /// The other end.
    pub b: [f64; 3],
    /// Radius.
    pub radius: f64,
}

impl Sdf for Capsule {
    fn distance(&self, p: [f64; 3]) -> f64 {
        let ab = sub(self.b, self.a);
        let t = (dot(sub(p, self.a), ab) / dot(ab, ab).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
        let q = [self.a[0] + t * ab[0], self.a[1] + t * ab[1], self.a[2] + t * ab[2]];
        norm(sub(p, q)) - self.radius
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let lo = std::array::from_fn(|k| self.a[k].min(self.b[k]) - self.radius);
        let hi = std::array::from_fn(|k| self.a[k].max(self.b[k]) + self.radius);
        (lo, hi)
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cuboid {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
}

impl Sdf for Cuboid {
    fn distance(&self, p: [f64; 3]) -> f64 {
        let c: [f64; 3] = std::array::from_fn(|k| 0.5 * (self.lo[k] + self.hi[k]));
        let h: [f64; 3] = std::array::from_fn(|k| 0.5 * (self.hi[k] - self.lo[k]));
        let q: [f64; 3] = std::array::from_fn(|k| (p[k] - c[k]).abs() - h[k]);
        let outside = norm(q.map(|x| x.max(0.0)));
        outside + q[0].max(q[1]).max(q[2]).min(0.0)
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.lo, self.hi)
    }
}

/// The union of several shapes (the minimum of their distances: exact outside, a bound
/// inside).
pub struct Union(pub Vec<Box<dyn Sdf>>);

impl Sdf for Union {
    fn distance(&self, p: [f64; 3]) -> f64 {
        self.0.iter().map(|s| s.distance(p)).fold(f64::INFINITY, f64::min)
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for s in &self.0 {
            let (a, b) = s.bounds();
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        (lo, hi)
    }
}

/// `outer` minus `hole` (max(d_outer, −d_hole)): a domain around an obstacle.
pub struct Difference {
    /// The domain.
    pub outer: Box<dyn Sdf>,
    /// What is cut out of it.
    pub hole: Box<dyn Sdf>,
}

impl Sdf for Difference {
    fn distance(&self, p: [f64; 3]) -> f64 {
        self.outer.distance(p).max(-self.hole.distance(p))
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.outer.bounds()
    }
}

/// The signed distance to a closed triangle surface read from an OBJ file (tobj): the
/// distance to the nearest triangle (a BVH's branch and bound), negative inside. Inside means
/// a ray from the point crosses the surface an odd number of times; three rays in unrelated
/// directions vote, so a ray through an edge or a vertex (counted twice or not at all) cannot
/// flip the sign alone. The surface must be closed (watertight); its triangles' orientation
/// does not matter.
pub struct ObjSurface {
    bvh: super::bvh::Bvh,
    lo: [f64; 3],
    hi: [f64; 3],
}

/// Three ray directions with no special relation to axes or to each other.
const RAYS: [[f64; 3]; 3] = [[0.5773, 0.6321, 0.5169], [-0.7013, 0.3127, 0.6406], [0.2113, -0.8619, 0.4608]];

impl ObjSurface {
    /// The surface from triangles (corner positions).
    pub fn from_triangles(triangles: Vec<[[f64; 3]; 3]>) -> Result<Self, MeshError> {
        if triangles.is_empty() {
            return Err(MeshError::Generation("a surface needs triangles".into()));
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (i, t) in triangles.iter().enumerate() {
            for p in t {
                if p.iter().any(|v| !v.is_finite()) {
                    return Err(MeshError::Generation(format!(
                        "surface triangle {i} has a coordinate that is not finite"
                    )));
                }
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let tris = triangles.into_iter().map(|t| t.map(glam::DVec3::from_array)).collect();
        Ok(Self { bvh: super::bvh::Bvh::new(tris), lo, hi })
    }

    /// Reads every object of an OBJ file (triangulated) as one surface; errors name the file.
    pub fn load(path: &std::path::Path) -> Result<Self, MeshError> {
        let models =
            super::obj::load(path).map_err(|e| MeshError::Generation(format!("{}: {e}", path.display())))?;
        let mut triangles = Vec::new();
        for m in &models {
            let pos = &m.mesh.positions;
            let corner = |i: u32| {
                let i = 3 * i as usize;
                [pos[i], pos[i + 1], pos[i + 2]]
            };
            for f in m.mesh.indices.chunks_exact(3) {
                triangles.push([corner(f[0]), corner(f[1]), corner(f[2])]);
            }
        }
        Self::from_triangles(triangles).map_err(|e| MeshError::Generation(format!("{}: {e}", path.display())))
    }

    /// Whether `p` is inside (majority of three rays with an odd number of crossings).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        let o = glam::DVec3::from_array(p);
        let odd =
            RAYS.iter().filter(|d| self.bvh.crossings(o, glam::DVec3::from_array(**d)) % 2 == 1).count();
        odd >= 2
    }
}

impl Sdf for ObjSurface {
    fn distance(&self, p: [f64; 3]) -> f64 {
        let d = self.bvh.nearest(glam::DVec3::from_array(p)).map_or(f64::INFINITY, |(d, _)| d);
        if self.contains(p) {
            -d
        } else {
            d
        }
    }
    fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        (self.lo, self.hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::stuffing::{dihedral_angles, stuff};

    /// A closed cube `[0, 1]³` as 12 triangles, written as an OBJ file.
    fn cube_obj(path: &std::path::Path) {
        let mut s = String::new();
        for z in 0..2 {
            for y in 0..2 {
                for x in 0..2 {
                    s += &format!("v {x} {y} {z}\n");
                }
            }
        }
        // Corner index = 1 + x + 2y + 4z; two triangles per face.
        for f in [[1, 3, 4, 2], [5, 6, 8, 7], [1, 2, 6, 5], [3, 7, 8, 4], [1, 5, 7, 3], [2, 4, 8, 6]] {
            s += &format!("f {} {} {}\nf {} {} {}\n", f[0], f[1], f[2], f[0], f[2], f[3]);
        }
        std::fs::write(path, s).expect("write cube");
    }

    #[test]
    fn an_obj_cube_has_the_signed_distance_of_a_box_and_stuffs_like_one() {
        let path = std::env::temp_dir().join(format!("galerkin-cube-{}.obj", std::process::id()));
        cube_obj(&path);
        let surface = ObjSurface::load(&path).expect("cube");
        let exact = Cuboid { lo: [0.0; 3], hi: [1.0; 3] };
        for p in [
            [0.5, 0.5, 0.5],
            [0.1, 0.7, 0.3],
            [1.5, 0.5, 0.5],
            [-0.3, -0.4, 1.2],
            [0.5, 0.5, 1.0 + 1e-9],
            [0.9, 0.2, 0.05],
        ] {
            let (a, b) = (surface.distance(p), exact.distance(p));
            assert!((a - b).abs() < 1e-12, "at {p:?}: {a} vs {b}");
        }
        // A box domain with the cube cut out: the volume between, to the stuffing's accuracy
        // (the cube's faces are planes on no lattice plane, its edges are rounded off).
        let domain = Difference {
            outer: Box::new(Cuboid { lo: [-0.6, -0.6, -0.6], hi: [1.6, 1.6, 1.6] }),
            hole: Box::new(surface),
        };
        let s = stuff(&domain, 0.1, &crate::mesh::budget::CellBudget::machine()).expect("stuffed");
        let vol: f64 = s.mesh.volumes().iter().sum();
        let want = 2.2f64.powi(3) - 1.0;
        assert!((vol - want).abs() < 0.02 * want, "volume {vol} vs {want}");
        let (mut lo, mut hi) = (180.0f64, 0.0f64);
        for c in 0..s.mesh.cell_count() {
            for a in dihedral_angles(&s.mesh.cell_points(c)) {
                lo = lo.min(a);
                hi = hi.max(a);
            }
        }
        assert!(lo >= 10.7 && hi <= 164.8, "dihedral angles {lo}° … {hi}°");
        crate::mesh::Topology::new(&s.mesh, None).expect("a manifold around the obstacle");
        assert!(ObjSurface::load(std::path::Path::new("/nonexistent/x.obj")).is_err());
        std::fs::remove_file(&path).expect("clean up");
    }
}
