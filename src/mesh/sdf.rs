//! Signed distance functions for isosurface stuffing ([`super::stuffing`]): negative inside,
//! positive outside, |∇| ≈ 1. Primitives (sphere, capsule, box) and their union and
//! difference — enough for the seed's cavity (§7.2: "we designed the cavity using simple
//! level set primitives").

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
