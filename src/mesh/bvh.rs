//! A bounding-volume hierarchy over triangles, built on the CPU (median splits on the longest
//! axis of the centroids' box): the segment test that decides the radiosity's `Vis(i, j)` of
//! seed 000 Eq. 15 (traversed here in f64 and, flattened to f32, in the compute shader
//! `radiosity/form_factors.comp`), the closest hit of a ray, and for signed distances to a
//! closed surface ([`super::sdf::ObjSurface`]) the nearest triangle and the number of
//! crossings of a ray.

use glam::DVec3;

/// Triangles per leaf at most.
const LEAF_SIZE: usize = 4;

/// One node of the flattened tree: its box, and either its children (`count == 0`: the left
/// child is the next node, the right child at `right_or_first`) or its triangles
/// (`count > 0`: `order[right_or_first ..][.. count]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BvhNode {
    /// Box minimum.
    pub lo: DVec3,
    /// Box maximum.
    pub hi: DVec3,
    /// Right child (inner node) or first triangle (leaf).
    pub right_or_first: u32,
    /// Triangles in a leaf; 0 for an inner node.
    pub count: u32,
}

/// The hierarchy and the triangles it holds.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes, depth first (a node's left child follows it).
    pub nodes: Vec<BvhNode>,
    /// Triangle indices in leaf order.
    pub order: Vec<u32>,
    /// Triangle corners, by triangle index.
    pub triangles: Vec<[DVec3; 3]>,
}

impl Bvh {
    /// Builds the hierarchy over `triangles`.
    pub fn new(triangles: Vec<[DVec3; 3]>) -> Self {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<DVec3> = triangles.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len() / LEAF_SIZE + 1);
        if !triangles.is_empty() {
            build(&triangles, &centroids, &mut order, 0, &mut nodes);
        }
        Self { nodes, order, triangles }
    }

    /// Walks the nodes whose boxes the ray `a + s·d` meets for `s ∈ [t_lo, limit()]`, depth
    /// first, handing each leaf triangle to `visit`; stops when `visit` says so. `limit` is
    /// asked again at every node (a closest-hit search shrinks it).
    fn walk(
        &self,
        a: DVec3,
        d: DVec3,
        t_lo: f64,
        limit: impl Fn() -> f64,
        mut visit: impl FnMut(u32) -> std::ops::ControlFlow<()>,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let index = stack[top];
            let node = &self.nodes[index as usize];
            if !slab(node.lo, node.hi, a, inv, t_lo, limit()) {
                continue;
            }
            if node.count == 0 {
                stack[top] = node.right_or_first;
                stack[top + 1] = index + 1;
                top += 2;
            } else {
                let first = node.right_or_first as usize;
                for &t in &self.order[first..first + node.count as usize] {
                    if visit(t).is_break() {
                        return;
                    }
                }
            }
        }
    }

    /// Whether the open segment from `a` to `b` (end points excluded by a relative margin)
    /// crosses any triangle other than `skip`.
    pub fn occluded(&self, a: DVec3, b: DVec3, skip: [u32; 2]) -> bool {
        let d = b - a;
        let (t_lo, t_hi) = (SEGMENT_MARGIN, 1.0 - SEGMENT_MARGIN);
        let mut hit = false;
        self.walk(
            a,
            d,
            t_lo,
            || t_hi,
            |t| {
                if t != skip[0] && t != skip[1] {
                    if let Some(s) = segment_triangle(a, d, &self.triangles[t as usize]) {
                        if s > t_lo && s < t_hi {
                            hit = true;
                            return std::ops::ControlFlow::Break(());
                        }
                    }
                }
                std::ops::ControlFlow::Continue(())
            },
        );
        hit
    }

    /// The nearest triangle the ray `origin + s·dir` (`s > 0`) meets from its front (the side
    /// its counter-clockwise corners face), and `s`: what a pixel of a back-face-culled
    /// rendering shows (the render test's reference).
    pub fn closest_front_hit(&self, origin: DVec3, dir: DVec3) -> Option<(u32, f64)> {
        let best = std::cell::Cell::new(None::<(u32, f64)>);
        let limit = || best.get().map_or(f64::INFINITY, |b| b.1);
        self.walk(origin, dir, 0.0, limit, |t| {
            let tri = &self.triangles[t as usize];
            if (tri[1] - tri[0]).cross(tri[2] - tri[0]).dot(dir) < 0.0 {
                if let Some(s) = segment_triangle(origin, dir, tri) {
                    if s > 0.0 && s < limit() {
                        best.set(Some((t, s)));
                    }
                }
            }
            std::ops::ControlFlow::Continue(())
        });
        best.get()
    }
}

impl Bvh {
    /// The distance from `p` to the nearest triangle and that triangle (branch and bound on
    /// the boxes' distances); `None` for an empty hierarchy.
    pub fn nearest(&self, p: DVec3) -> Option<(f64, u32)> {
        if self.nodes.is_empty() {
            return None;
        }
        let box_distance = |n: &BvhNode| (n.lo - p).max(p - n.hi).max(DVec3::ZERO).length();
        let mut best = (f64::INFINITY, 0u32);
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index as usize];
            if box_distance(node) >= best.0 {
                continue;
            }
            if node.count == 0 {
                // Nearer child last, so it is visited first.
                let (l, r) = (index + 1, node.right_or_first);
                let (dl, dr) = (box_distance(&self.nodes[l as usize]), box_distance(&self.nodes[r as usize]));
                if dl < dr {
                    stack.extend([r, l]);
                } else {
                    stack.extend([l, r]);
                }
            } else {
                let first = node.right_or_first as usize;
                for &t in &self.order[first..first + node.count as usize] {
                    let d = point_triangle_distance(p, &self.triangles[t as usize]);
                    if d < best.0 {
                        best = (d, t);
                    }
                }
            }
        }
        Some(best)
    }

    /// How many triangles the ray `origin + s·dir` (`s > 0`) crosses.
    pub fn crossings(&self, origin: DVec3, dir: DVec3) -> usize {
        let mut n = 0;
        self.walk(
            origin,
            dir,
            0.0,
            || f64::INFINITY,
            |t| {
                if segment_triangle(origin, dir, &self.triangles[t as usize]).is_some_and(|s| s > 0.0) {
                    n += 1;
                }
                std::ops::ControlFlow::Continue(())
            },
        );
        n
    }
}

/// Distance from `p` to the triangle `t`.
pub fn point_triangle_distance(p: DVec3, t: &[DVec3; 3]) -> f64 {
    let w = closest_point_weights(p, t);
    (p - (t[0] * w[0] + t[1] * w[1] + t[2] * w[2])).length()
}

/// The barycentric weights of the point of triangle `t` closest to `p` (Ericson's
/// closest-point regions: a vertex, an edge or the interior).
pub fn closest_point_weights(p: DVec3, t: &[DVec3; 3]) -> [f64; 3] {
    let (a, b, c) = (t[0], t[1], t[2]);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    [1.0 - v - w, v, w]
}

/// The part of the segment cut off at each end, relative to its length: rays start and end on
/// the two faces themselves, so their own planes must not count.
pub const SEGMENT_MARGIN: f64 = 1e-7;

fn build(
    tris: &[[DVec3; 3]],
    centroids: &[DVec3],
    order: &mut [u32],
    first: usize,
    nodes: &mut Vec<BvhNode>,
) -> usize {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &t in order.iter() {
        for p in tris[t as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        clo = clo.min(centroids[t as usize]);
        chi = chi.max(centroids[t as usize]);
    }
    let me = nodes.len();
    nodes.push(BvhNode { lo, hi, right_or_first: first as u32, count: order.len() as u32 });
    let extent = chi - clo;
    if order.len() <= LEAF_SIZE || extent.max_element() <= 0.0 {
        return me;
    }
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |a, b| {
        centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
    });
    let (left, right) = order.split_at_mut(mid);
    build(tris, centroids, left, first, nodes);
    let r = build(tris, centroids, right, first + mid, nodes);
    nodes[me].right_or_first = r as u32;
    nodes[me].count = 0;
    me
}

/// Whether the segment `a + s·d`, `s ∈ [t_lo, t_hi]`, meets the box (slab test; `inv = 1/d`).
fn slab(lo: DVec3, hi: DVec3, a: DVec3, inv: DVec3, t_lo: f64, t_hi: f64) -> bool {
    let t0 = (lo - a) * inv;
    let t1 = (hi - a) * inv;
    let near = t0.min(t1).max_element().max(t_lo);
    let far = t0.max(t1).min_element().min(t_hi);
    // NaN (0·∞ for a segment in a box's face plane) is unordered: treat it as a hit.
    near.partial_cmp(&far) != Some(std::cmp::Ordering::Greater)
}

/// Möller–Trumbore: the parameter `s` where `a + s·d` meets the triangle, edges included.
pub fn segment_triangle(a: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<f64> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = a - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv)
}
