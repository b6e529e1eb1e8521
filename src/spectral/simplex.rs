//! Lagrange triangles and tetrahedra of order 1–10 on equispaced nodes, as VTK writes them
//! (`VTK_LAGRANGE_TRIANGLE` = 69, `VTK_LAGRANGE_TETRAHEDRON` = 71): the nodes in VTK's point
//! order and the basis with its reference gradient, in f64 — the CPU reference for drawing
//! high-order simplices per pixel like the quadrilaterals and hexahedra of seed 002.
//!
//! **Reference element.** The triangle `r₀, r₁ ≥ 0, r₀ + r₁ ≤ 1`, the tetrahedron
//! `r₀, r₁, r₂ ≥ 0, r₀ + r₁ + r₂ ≤ 1` (VTK's parametric coordinates). A node of order n is a
//! multi-index `b` of barycentric integers summing to n; its point is `r_a = b_a / n` for
//! the first `d` entries, the last entry being the remainder `n − Σ` (the weight of vertex 0).
//!
//! **VTK's order** is recursive in shells: the shell's vertices (vertex 0 at the origin, then
//! one per axis), the points inside each edge from its first vertex to its second, then — on a
//! tetrahedron — the points inside each face, ordered as a triangle of order n − 3 placed on
//! the face's vertices, and finally the interior, which is the same element of order
//! n − 3 (triangle) or n − 4 (tetrahedron) one layer in. Edges (vertex pairs) and faces (vertex
//! triples, in the order the inner triangle's vertices 0, 1, 2 take) are VTK's tetrahedron's.
//! `tests/spectral_simplex.rs` checks every point of orders 1–10 against the parametric
//! coordinates VTK 9.7 itself gives (`scripts/vtk-simplex-fixtures.py`).
//!
//! **Basis** (Silvester's formula): the node `b` has `L_b(λ) = Π_a R_{b_a}(λ_a)` with
//! `R_k(λ) = Π_{m<k} (nλ − m)/(m + 1)` of the barycentric coordinates λ; `R_k(j/n)` is the
//! binomial `C(j, k)` (0 for j < k), so `L_b` is 1 at its node and 0 at every other.
//!
//! **Bézier simplices** (`VTK_BEZIER_TRIANGLE` = 76, `VTK_BEZIER_TETRAHEDRON` = 78) number
//! their control points as the Lagrange ones; their basis is Bernstein's,
//! `B_b = n!/Π b_a! Π λ_a^{b_a}` ([`bernstein_basis`]). They span the same polynomials, so
//! [`FromBernstein`] turns one into the Lagrange element that equals it, and [`ToBernstein`]
//! goes back.

use super::error::SpectralError;

/// The highest order of a simplex read or drawn.
pub const MAX_SIMPLEX_ORDER: usize = 10;

/// A simplex shape.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum SimplexShape {
    /// The triangle (d = 2).
    Triangle,
    /// The tetrahedron (d = 3).
    Tetrahedron,
}

impl SimplexShape {
    /// Reference dimension d.
    pub fn dim(self) -> usize {
        match self {
            Self::Triangle => 2,
            Self::Tetrahedron => 3,
        }
    }

    /// Nodes of order `n`: (n+1)(n+2)/2 or (n+1)(n+2)(n+3)/6.
    pub fn node_count(self, n: usize) -> usize {
        match self {
            Self::Triangle => (n + 1) * (n + 2) / 2,
            Self::Tetrahedron => (n + 1) * (n + 2) * (n + 3) / 6,
        }
    }
}

/// The vertices of the reference tetrahedron by the barycentric entry they carry: vertex 0 is
/// the remainder (entry 3), vertices 1–3 the axes (entries 0–2); the triangle's likewise with
/// entries 2, 0, 1.
const TETRA_VERTEX_ENTRY: [usize; 4] = [3, 0, 1, 2];
const TRIANGLE_VERTEX_ENTRY: [usize; 3] = [2, 0, 1];
/// VTK's tetrahedron edges (vertex pairs, traversed first to second).
const TETRA_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
/// VTK's tetrahedron faces, as the vertices the inner triangle's vertices 0, 1, 2 sit on.
const TETRA_FACES: [[usize; 3]; 4] = [[0, 1, 3], [2, 3, 1], [0, 3, 2], [0, 2, 1]];

/// The barycentric multi-indices of the nodes of order `n` in VTK's point order (entries past
/// the shape's d + 1 are 0); refuses orders outside 1 to [`MAX_SIMPLEX_ORDER`].
pub fn vtk_nodes(shape: SimplexShape, n: usize) -> Result<Vec<[usize; 4]>, SpectralError> {
    if n == 0 || n > MAX_SIMPLEX_ORDER {
        return Err(SpectralError::Order {
            what: format!("Lagrange {shape:?}"),
            order: n,
            max: MAX_SIMPLEX_ORDER,
        });
    }
    let mut out = Vec::with_capacity(shape.node_count(n));
    match shape {
        SimplexShape::Triangle => triangle_shell(n as isize, 0, &mut out),
        SimplexShape::Tetrahedron => tetra_shell(n as isize, 0, &mut out),
    }
    Ok(out)
}

/// A point of a shell: every entry `low`, plus `extra[v]` on vertex v's entry.
fn shell_point(entries: &[usize], low: isize, extra: &[(usize, isize)]) -> [usize; 4] {
    let mut b = [0isize; 4];
    for &e in entries {
        b[e] = low;
    }
    for &(v, x) in extra {
        b[entries[v]] += x;
    }
    b.map(|x| x.max(0) as usize)
}

/// The triangle's shell of order `s` whose entries start at `low`, then the shells inside.
fn triangle_shell(s: isize, low: isize, out: &mut Vec<[usize; 4]>) {
    let e = &TRIANGLE_VERTEX_ENTRY;
    if s == 0 {
        out.push(shell_point(e, low, &[]));
        return;
    }
    for v in 0..3 {
        out.push(shell_point(e, low, &[(v, s)]));
    }
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        for k in 1..s {
            out.push(shell_point(e, low, &[(a, s - k), (b, k)]));
        }
    }
    if s >= 3 {
        triangle_shell(s - 3, low + 1, out);
    }
}

/// The tetrahedron's shell of order `s` whose entries start at `low`, then the shells inside.
fn tetra_shell(s: isize, low: isize, out: &mut Vec<[usize; 4]>) {
    let e = &TETRA_VERTEX_ENTRY;
    if s == 0 {
        out.push(shell_point(e, low, &[]));
        return;
    }
    for v in 0..4 {
        out.push(shell_point(e, low, &[(v, s)]));
    }
    for [a, b] in TETRA_EDGES {
        for k in 1..s {
            out.push(shell_point(e, low, &[(a, s - k), (b, k)]));
        }
    }
    if s >= 3 {
        // Each face's inside: a triangle of order s − 3 whose vertex i sits on face vertex i,
        // every one of its points one step in from the face's edges.
        let mut inner = Vec::new();
        triangle_shell(s - 3, 0, &mut inner);
        for face in TETRA_FACES {
            for p in &inner {
                let weight = |i: usize| p[TRIANGLE_VERTEX_ENTRY[i]] as isize + 1;
                out.push(shell_point(
                    e,
                    low,
                    &[(face[0], weight(0)), (face[1], weight(1)), (face[2], weight(2))],
                ));
            }
        }
    }
    if s >= 4 {
        tetra_shell(s - 4, low + 1, out);
    }
}

/// The reference point of node `b` of order `n` (the first d entries over n).
pub fn node_point(shape: SimplexShape, n: usize, b: &[usize; 4]) -> [f64; 3] {
    let mut r = [0.0; 3];
    for (a, x) in r.iter_mut().enumerate().take(shape.dim()) {
        *x = b[a] as f64 / n as f64;
    }
    r
}

/// `R_k(λ)` and its derivative in λ for order `n` (Silvester's factor, see the module docs).
fn silvester(n: usize, k: usize, lambda: f64) -> (f64, f64) {
    let (mut value, mut derivative) = (1.0, 0.0);
    for m in 0..k {
        let factor = (n as f64 * lambda - m as f64) / (m + 1) as f64;
        let dfactor = n as f64 / (m + 1) as f64;
        derivative = derivative * factor + value * dfactor;
        value *= factor;
    }
    (value, derivative)
}

/// The barycentric coordinates of reference point `r`: `λ_a = r_a` for a < d and
/// `λ_d = 1 − Σ r` (so `∂λ_d/∂r_j = −1`); entries past d are 0.
fn barycentric(shape: SimplexShape, r: &[f64; 3]) -> [f64; 4] {
    let d = shape.dim();
    let mut lambda = [0.0; 4];
    lambda[..d].copy_from_slice(&r[..d]);
    lambda[d] = 1.0 - r[..d].iter().sum::<f64>();
    lambda
}

/// The basis of order `n` at reference point `r` for the nodes `nodes` (from [`vtk_nodes`]):
/// each node's value and its gradient in r (d entries used).
pub fn basis(shape: SimplexShape, n: usize, nodes: &[[usize; 4]], r: &[f64; 3]) -> Vec<(f64, [f64; 3])> {
    let d = shape.dim();
    let lambda = barycentric(shape, r);
    nodes
        .iter()
        .map(|b| {
            let factors: Vec<(f64, f64)> = (0..=d).map(|a| silvester(n, b[a], lambda[a])).collect();
            let value: f64 = factors.iter().map(|f| f.0).product();
            // ∂L/∂λ_a = R'_a Π_{c≠a} R_c.
            let dl = |a: usize| -> f64 {
                factors.iter().enumerate().map(|(c, f)| if c == a { f.1 } else { f.0 }).product()
            };
            let last = dl(d);
            let mut gradient = [0.0; 3];
            for (j, g) in gradient.iter_mut().enumerate().take(d) {
                *g = dl(j) - last;
            }
            (value, gradient)
        })
        .collect()
}

/// The 1D factors of Silvester's basis at one barycentric coordinate: `v[k] = R_k(λ)` for
/// k = 0..=n and, when asked, `d[k] = R_k′(λ)` (the recurrence
/// `R_k = R_{k−1} (nλ − k + 1)/k`). A triangle's basis is a product of three such rows
/// ([`triangle_terms`]), as a quadrilateral's is of two 1D bases. Twin of `simplex_silvester`
/// (shaders-glsl/include/spectral_simplex.glsl).
pub fn silvester_row(n: usize, lambda: f64, v: &mut [f64], mut d: Option<&mut [f64]>) {
    v[0] = 1.0;
    if let Some(d) = d.as_deref_mut() {
        d[0] = 0.0;
    }
    for k in 1..=n {
        let factor = (n as f64 * lambda - (k - 1) as f64) / k as f64;
        if let Some(d) = d.as_deref_mut() {
            d[k] = d[k - 1] * factor + v[k - 1] * n as f64 / k as f64;
        }
        v[k] = v[k - 1] * factor;
    }
}

/// Where node (i, j) of a triangle of order `n` (i + j ≤ n; its point (i/n, j/n)) sits in an
/// element's run of a [`super::SpectralMesh`]: rows of constant j, i fastest, so
/// `j (n + 1) − j (j − 1)/2 + i`. Loaders reorder VTK's order into this one.
pub fn triangle_index(n: usize, i: usize, j: usize) -> usize {
    j * (n + 1) - j * j.saturating_sub(1) / 2 + i
}

/// For each of VTK's points of a triangle of order `n` (VTK's order), its position in our
/// layout ([`triangle_index`]).
pub fn triangle_from_vtk(n: usize) -> Result<Vec<usize>, SpectralError> {
    Ok(vtk_nodes(SimplexShape::Triangle, n)?.iter().map(|b| triangle_index(n, b[0], b[1])).collect())
}

/// Calls `visit(k, L, [∂L/∂ξ, ∂L/∂η])` for every node k (our layout) of a triangle of order
/// `n` at r = (ξ, η): `L_ij = R_i(ξ) R_j(η) R_{n−i−j}(1 − ξ − η)` (Silvester), the sums of a
/// geometry map, a field or their derivatives. Twin of the sums in spectral_simplex.glsl.
pub fn triangle_terms(n: usize, r: [f64; 2], mut visit: impl FnMut(usize, f64, [f64; 2])) {
    let (mut a, mut da, mut b, mut db, mut c, mut dc) =
        ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
    silvester_row(n, r[0], &mut a, Some(&mut da));
    silvester_row(n, r[1], &mut b, Some(&mut db));
    silvester_row(n, 1.0 - r[0] - r[1], &mut c, Some(&mut dc));
    let mut k = 0;
    for j in 0..=n {
        for i in 0..=n - j {
            let l = n - i - j;
            let value = a[i] * b[j] * c[l];
            let dxi = da[i] * b[j] * c[l] - a[i] * b[j] * dc[l];
            let deta = a[i] * db[j] * c[l] - a[i] * b[j] * dc[l];
            visit(k, value, [dxi, deta]);
            k += 1;
        }
    }
}

/// Where node (i, j, k) of a tetrahedron of order `n` (i + j + k ≤ n; its point
/// (i, j, k)/n) sits in an element's run of a [`super::SpectralMesh`]: layers of constant k,
/// each a triangle of order n − k in [`triangle_index`]'s rows.
pub fn tetra_index(n: usize, i: usize, j: usize, k: usize) -> usize {
    (0..k).map(|l| SimplexShape::Triangle.node_count(n - l)).sum::<usize>() + triangle_index(n - k, i, j)
}

/// For each of VTK's points of a tetrahedron of order `n` (VTK's order), its position in our
/// layout ([`tetra_index`]).
pub fn tetra_from_vtk(n: usize) -> Result<Vec<usize>, SpectralError> {
    Ok(vtk_nodes(SimplexShape::Tetrahedron, n)?.iter().map(|b| tetra_index(n, b[0], b[1], b[2])).collect())
}

/// [`triangle_terms`] for a tetrahedron of order `n` at r = (ξ, η, ζ): every node k (our
/// layout) with `L = R_i(ξ) R_j(η) R_k(ζ) R_{n−i−j−k}(1 − ξ − η − ζ)` and its gradient.
pub fn tetra_terms(n: usize, r: [f64; 3], mut visit: impl FnMut(usize, f64, [f64; 3])) {
    let mut v = [[0.0; 16]; 4];
    let mut d = [[0.0; 16]; 4];
    let lambda = [r[0], r[1], r[2], 1.0 - r[0] - r[1] - r[2]];
    for a in 0..4 {
        silvester_row(n, lambda[a], &mut v[a], Some(&mut d[a]));
    }
    let mut index = 0;
    for k in 0..=n {
        for j in 0..=n - k {
            for i in 0..=n - k - j {
                let l = n - i - j - k;
                let (a, b, c, w) = (v[0][i], v[1][j], v[2][k], v[3][l]);
                let dw = d[3][l];
                let value = a * b * c * w;
                let gradient = [
                    d[0][i] * b * c * w - a * b * c * dw,
                    a * d[1][j] * c * w - a * b * c * dw,
                    a * b * d[2][k] * w - a * b * c * dw,
                ];
                visit(index, value, gradient);
                index += 1;
            }
        }
    }
}

/// From a simplex's values at its Lagrange nodes to its Bernstein coefficients, for one shape
/// and order: the inverse of the collocation matrix `V[node][b] = B_b(node)`, with
/// `B_b = n!/Π b_a! Π λ_a^{b_a}`, formed once and applied to every element. The control points
/// it gives have a convex hull that contains the element (the Bernstein polynomials are
/// non-negative and sum to 1), which is what the cut pass tests planes against.
pub struct ToBernstein {
    count: usize,
    /// The inverse, row-major.
    inverse: Vec<f64>,
}

impl ToBernstein {
    /// The conversion for `shape` of order `n` (nodes in our layout, [`lattice`]); `None` if
    /// the collocation matrix is singular (it is not, for distinct equispaced nodes).
    pub fn new(shape: SimplexShape, n: usize) -> Option<Self> {
        use faer::linalg::solvers::Solve;
        let (count, collocation) = collocation(shape, n);
        let matrix = faer::Mat::from_fn(count, count, |row, col| collocation[row * count + col]);
        let inverse = matrix.partial_piv_lu().solve(faer::Mat::<f64>::identity(count, count));
        let inverse: Vec<f64> = (0..count * count).map(|k| inverse[(k / count, k % count)]).collect();
        inverse.iter().all(|x| x.is_finite()).then_some(Self { count, inverse })
    }

    /// The Bernstein coefficients of a scalar whose values at the nodes (our layout) are
    /// `values`.
    pub fn control_values(&self, values: &[f64]) -> Vec<f64> {
        apply(self.count, &self.inverse, values)
    }

    /// The Bernstein control points of an element whose nodes (our layout) are at `points`.
    pub fn control_points(&self, points: &[[f64; 3]]) -> Vec<[f64; 3]> {
        per_component(points, |v| self.control_values(v))
    }
}

/// `B_b(λ) = n!/Π b_a! Π λ_a^{b_a}`, the Bernstein polynomial of multi-index `b` (entries
/// 0..=d used; order n = Σ b) at barycentric coordinates λ.
fn bernstein(d: usize, b: &[usize; 4], lambda: &[f64; 4]) -> f64 {
    let factorial = |m: usize| (1..=m).map(|x| x as f64).product::<f64>();
    let n: usize = b[..=d].iter().sum();
    let mut v = factorial(n);
    for a in 0..=d {
        v *= lambda[a].powi(b[a] as i32) / factorial(b[a]);
    }
    v
}

/// The Bernstein basis of order `n` at reference point `r` for the multi-indices `nodes`
/// (from [`vtk_nodes`]: a Bézier simplex's control points in VTK's point order), each with its
/// gradient in r: `∂B_b/∂λ_a = n B^{n−1}_{b−e_a}` and `∂/∂r_j = ∂/∂λ_j − ∂/∂λ_d`. The plain
/// evaluation of VTK's `vtkBezierTriangle` / `vtkBezierTetra` (types 76 and 78).
pub fn bernstein_basis(
    shape: SimplexShape,
    n: usize,
    nodes: &[[usize; 4]],
    r: &[f64; 3],
) -> Vec<(f64, [f64; 3])> {
    let d = shape.dim();
    let lambda = barycentric(shape, r);
    nodes
        .iter()
        .map(|b| {
            let dl = |a: usize| -> f64 {
                if b[a] == 0 {
                    return 0.0;
                }
                let mut lower = *b;
                lower[a] -= 1;
                n as f64 * bernstein(d, &lower, &lambda)
            };
            let last = dl(d);
            let mut gradient = [0.0; 3];
            for (j, g) in gradient.iter_mut().enumerate().take(d) {
                *g = dl(j) - last;
            }
            (bernstein(d, b, &lambda), gradient)
        })
        .collect()
}

/// The collocation matrix of order `n`, row-major: `V[node][b] = B_b(node)` over the nodes of
/// our layout ([`lattice`]) and the Bernstein polynomials of the same multi-indices.
fn collocation(shape: SimplexShape, n: usize) -> (usize, Vec<f64>) {
    let lattice = lattice(shape, n);
    let count = lattice.len();
    let mut matrix = Vec::with_capacity(count * count);
    for node in &lattice {
        let lambda: [f64; 4] = std::array::from_fn(|a| node[a] as f64 / n as f64);
        matrix.extend(lattice.iter().map(|b| bernstein(shape.dim(), b, &lambda)));
    }
    (count, matrix)
}

/// A linear map of scalars per node (`convert`) applied to each coordinate of `points`, and
/// the results zipped back into points (as many as `convert` returns).
pub fn per_component(points: &[[f64; 3]], convert: impl Fn(&[f64]) -> Vec<f64>) -> Vec<[f64; 3]> {
    let per: [Vec<f64>; 3] =
        std::array::from_fn(|c| convert(&points.iter().map(|p| p[c]).collect::<Vec<_>>()));
    (0..per[0].len()).map(|k| [per[0][k], per[1][k], per[2][k]]).collect()
}

/// `matrix · values` for a row-major matrix of rows `columns` long.
pub(super) fn apply(columns: usize, matrix: &[f64], values: &[f64]) -> Vec<f64> {
    matrix.chunks_exact(columns).map(|row| row.iter().zip(values).map(|(w, v)| w * v).sum()).collect()
}

/// From a Bézier simplex's control values to its values at the Lagrange nodes (our layout):
/// the collocation matrix `V[node][b] = B_b(node)` itself. The same polynomial space, so a
/// Bézier triangle or tetrahedron (VTK types 76 and 78) is drawn as the Lagrange element of
/// its order that equals it exactly (up to rounding: entries of V lie in [0, 1], each row sums
/// to 1). The inverse of [`ToBernstein`].
pub struct FromBernstein {
    count: usize,
    matrix: Vec<f64>,
}

impl FromBernstein {
    /// The conversion for `shape` of order `n` (1 to [`MAX_SIMPLEX_ORDER`]).
    pub fn new(shape: SimplexShape, n: usize) -> Self {
        let (count, matrix) = collocation(shape, n);
        Self { count, matrix }
    }

    /// The values at the nodes (our layout) of the polynomial whose Bernstein coefficients
    /// (our layout) are `control`.
    pub fn nodal_values(&self, control: &[f64]) -> Vec<f64> {
        apply(self.count, &self.matrix, control)
    }

    /// The nodes (our layout) of the element whose control points (our layout) are `control`.
    pub fn nodal_points(&self, control: &[[f64; 3]]) -> Vec<[f64; 3]> {
        per_component(control, |v| self.nodal_values(v))
    }
}

/// The barycentric multi-indices (entries 0..d the node's (i, j[, k]), entry d the remainder)
/// of every node of order `n` in our layout.
pub fn lattice(shape: SimplexShape, n: usize) -> Vec<[usize; 4]> {
    let mut out = Vec::with_capacity(shape.node_count(n));
    match shape {
        SimplexShape::Triangle => {
            for j in 0..=n {
                for i in 0..=n - j {
                    out.push([i, j, n - i - j, 0]);
                }
            }
        }
        SimplexShape::Tetrahedron => {
            for k in 0..=n {
                for j in 0..=n - k {
                    for i in 0..=n - k - j {
                        out.push([i, j, k, n - i - j - k]);
                    }
                }
            }
        }
    }
    out
}
