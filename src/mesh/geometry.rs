//! The geometry of one simplex, dimension-generic (triangles in 2D, tetrahedra in 3D): signed
//! volume, outward area normals of its faces, centroids. Points are `[f64; 3]` with z = 0 in
//! 2D, so one code path serves both dimensions.
//!
//! The identity used throughout: the outward area normal of the face opposite vertex k is
//! `A_k n_k = −d ∂vol/∂x_k` (d the dimension), and these sum to zero over the faces.

/// A point; z is 0 in 2D.
pub type Point = [f64; 3];

/// Signed volume (area in 2D) of the simplex `p` (`dim + 1` points): `det[p₁−p₀, …]/d!`,
/// positive when the vertices are in counter-clockwise (2D) or right-handed (3D) order
/// (seed 000 Eq. 7: the diagonal entries `v_k(g)` of the volume tensor).
pub fn signed_volume(dim: usize, p: &[Point]) -> f64 {
    let e = |i: usize, k: usize| p[i][k] - p[0][k];
    match dim {
        2 => 0.5 * (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0)),
        3 => {
            (e(1, 0) * (e(2, 1) * e(3, 2) - e(2, 2) * e(3, 1))
                - e(1, 1) * (e(2, 0) * e(3, 2) - e(2, 2) * e(3, 0))
                + e(1, 2) * (e(2, 0) * e(3, 1) - e(2, 1) * e(3, 0)))
                / 6.0
        }
        _ => panic!("simplices of dimension 2 or 3 only"),
    }
}

/// Outward area normal of the face opposite vertex `k` (its length is the face's area; length
/// in 2D) for a positively oriented simplex: `−d ∂vol/∂x_k`.
pub fn face_area_normal(dim: usize, p: &[Point], k: usize) -> Point {
    match dim {
        2 => {
            // Counter-clockwise triangle: the edge a → b opposite k, outward = (b − a) turned
            // clockwise.
            let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
            [b[1] - a[1], -(b[0] - a[0]), 0.0]
        }
        3 => {
            let sub = |a: Point, b: Point| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            let cross = |a: Point, b: Point| {
                [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            };
            // ∂(6 vol)/∂x_k for k = 1, 2, 3; x_0's is minus their sum. Outward = −½ of it.
            let grad = |k: usize| match k {
                1 => cross(sub(p[2], p[0]), sub(p[3], p[0])),
                2 => cross(sub(p[3], p[0]), sub(p[1], p[0])),
                _ => cross(sub(p[1], p[0]), sub(p[2], p[0])),
            };
            let g = if k == 0 {
                let (a, b, c) = (grad(1), grad(2), grad(3));
                [-(a[0] + b[0] + c[0]), -(a[1] + b[1] + c[1]), -(a[2] + b[2] + c[2])]
            } else {
                grad(k)
            };
            [-0.5 * g[0], -0.5 * g[1], -0.5 * g[2]]
        }
        _ => panic!("simplices of dimension 2 or 3 only"),
    }
}

/// Centroid of the points.
pub fn centroid(p: &[Point]) -> Point {
    let mut c = [0.0; 3];
    for q in p {
        for k in 0..3 {
            c[k] += q[k];
        }
    }
    c.map(|x| x / p.len() as f64)
}

/// Centroid of the face opposite vertex `k`.
pub fn face_centroid(p: &[Point], k: usize) -> Point {
    let mut c = [0.0; 3];
    for (i, q) in p.iter().enumerate() {
        if i != k {
            for j in 0..3 {
                c[j] += q[j];
            }
        }
    }
    c.map(|x| x / (p.len() - 1) as f64)
}

/// Volume swept by the face opposite `k` as the simplex moves linearly from `p0` to `p1`,
/// positive when the face moves outward (seed 000 Eq. 11 integrated over the frame:
/// `∫ A n · ċ dτ`). The area normal is quadratic in τ and the centroid velocity constant, so
/// Simpson's rule is exact; summed over the faces it is exactly `vol(p1) − vol(p0)`.
pub fn swept_volume(dim: usize, p0: &[Point], p1: &[Point], k: usize) -> f64 {
    let mid: Vec<Point> = p0
        .iter()
        .zip(p1)
        .map(|(a, b)| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])])
        .collect();
    let (n0, nm, n1) =
        (face_area_normal(dim, p0, k), face_area_normal(dim, &mid, k), face_area_normal(dim, p1, k));
    let (c0, c1) = (face_centroid(p0, k), face_centroid(p1, k));
    (0..3).map(|i| (n0[i] + 4.0 * nm[i] + n1[i]) / 6.0 * (c1[i] - c0[i])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tet() -> Vec<Point> {
        vec![[0.1, 0.0, 0.2], [1.3, 0.1, 0.0], [0.2, 1.1, 0.3], [0.0, 0.4, 0.9]]
    }

    #[test]
    fn area_normals_are_minus_d_times_the_volume_gradient_and_sum_to_zero() {
        for (dim, p) in [(2, vec![[0.0, 0.0, 0.0], [1.0, 0.2, 0.0], [0.3, 0.8, 0.0]]), (3, tet())] {
            let v = signed_volume(dim, &p);
            assert!(v > 0.0);
            let mut sum = [0.0; 3];
            for k in 0..=dim {
                let n = face_area_normal(dim, &p, k);
                for axis in 0..dim {
                    let h = 1e-6;
                    let mut q = p.clone();
                    q[k][axis] += h;
                    let vp = signed_volume(dim, &q);
                    q[k][axis] -= 2.0 * h;
                    let vm = signed_volume(dim, &q);
                    let grad = (vp - vm) / (2.0 * h);
                    assert!((n[axis] + dim as f64 * grad).abs() < 1e-9, "dim {dim} face {k} axis {axis}");
                    sum[axis] += n[axis];
                }
            }
            assert!(sum.iter().all(|s| s.abs() < 1e-14));
        }
    }

    #[test]
    fn swept_volumes_add_up_to_the_change_of_volume() {
        for dim in [2, 3] {
            let p0: Vec<Point> = tet()
                .into_iter()
                .take(dim + 1)
                .map(|mut q| {
                    if dim == 2 {
                        q[2] = 0.0;
                    }
                    q
                })
                .collect();
            let p1: Vec<Point> = p0
                .iter()
                .enumerate()
                .map(|(i, q)| {
                    let s = 0.3 * (i as f64 + 1.0);
                    [q[0] + 0.2 * s, q[1] - 0.1 * s * s, if dim == 3 { q[2] + 0.15 * s } else { 0.0 }]
                })
                .collect();
            let total: f64 = (0..=dim).map(|k| swept_volume(dim, &p0, &p1, k)).sum();
            let dv = signed_volume(dim, &p1) - signed_volume(dim, &p0);
            assert!((total - dv).abs() < 1e-14, "dim {dim}: {total} vs {dv}");
        }
    }
}
