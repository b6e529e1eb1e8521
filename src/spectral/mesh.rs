//! A spectral-element data set (seed 002) of quadrilaterals, hexahedra or Lagrange triangles
//! (node order and basis in [`super::simplex`]): per element a
//! tensor-product geometry map x(ξ, η) = Σ_ij X_ij g_i(ξ) g_j(η) (hexahedra: x(ξ, η, ζ) =
//! Σ_ijk X_ijk g_i(ξ) g_j(η) g_k(ζ)) of its own order and node set, and any number of scalar
//! fields, each with any number of time steps, as tensor-product polynomials
//! f = Σ F_ij ℓ_i(ξ) ℓ_j(η) (Σ F_ijk ℓ_i ℓ_j ℓ_k) on the reference square [0, 1]² (cube
//! [0, 1]³). This module is also the CPU f64 reference the renderer is tested against: the
//! map, its Jacobian, its inverse (Newton's method in f64) and the field values.
//!
//! Node (i, j) of element e is entry `e m² + j m + i` (m = order + 1, i along ξ fastest), node
//! (i, j, k) of a hexahedron `e m³ + k m² + j m + i`, for geometry points and field values
//! alike. Loaders reorder other conventions into this one.

use super::basis::Basis1d;
use super::error::SpectralError;

/// One scalar field over the mesh, at one or more time steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    /// Its name (`--field NAME`).
    pub name: String,
    /// The time of each step.
    pub times: Vec<f64>,
    /// Per step, the coefficients of every element: elements × (n + 1)² values.
    pub steps: Vec<Vec<f64>>,
}

/// The reference shape of every element of a mesh.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Quadrilaterals, (ξ, η) ∈ [0, 1]², in the plane or embedded in 3D.
    Quadrilateral,
    /// Hexahedra, (ξ, η, ζ) ∈ [0, 1]³.
    Hexahedron,
    /// Lagrange triangles on equispaced nodes (VTK's `VTK_LAGRANGE_TRIANGLE`), ξ, η ≥ 0,
    /// ξ + η ≤ 1, in the plane; node (i, j) at [`super::simplex::triangle_index`], the basis
    /// Silvester's ([`super::simplex::triangle_terms`]).
    Triangle,
    /// Lagrange tetrahedra on equispaced nodes (VTK's `VTK_LAGRANGE_TETRAHEDRON`), ξ, η, ζ ≥ 0,
    /// ξ + η + ζ ≤ 1; node (i, j, k) at [`super::simplex::tetra_index`], drawn by cut planes
    /// like hexahedra ([`super::simplex::tetra_terms`]).
    Tetrahedron,
}

impl From<super::simplex::SimplexShape> for Shape {
    fn from(s: super::simplex::SimplexShape) -> Self {
        match s {
            super::simplex::SimplexShape::Triangle => Self::Triangle,
            super::simplex::SimplexShape::Tetrahedron => Self::Tetrahedron,
        }
    }
}

impl Shape {
    /// Reference dimension: 2 or 3.
    pub fn dim(self) -> u32 {
        match self {
            Self::Quadrilateral | Self::Triangle => 2,
            Self::Hexahedron | Self::Tetrahedron => 3,
        }
    }

    /// Whether the elements are solids (hexahedra or tetrahedra, shown by cut planes).
    pub fn is_volume(self) -> bool {
        self.dim() == 3
    }

    /// Whether the elements are simplices (triangles or tetrahedra).
    pub fn is_simplex(self) -> bool {
        matches!(self, Self::Triangle | Self::Tetrahedron)
    }

    /// The simplex shape of triangles and tetrahedra ([`super::simplex`]); `None` otherwise.
    pub fn simplex(self) -> Option<super::simplex::SimplexShape> {
        match self {
            Self::Triangle => Some(super::simplex::SimplexShape::Triangle),
            Self::Tetrahedron => Some(super::simplex::SimplexShape::Tetrahedron),
            _ => None,
        }
    }

    /// Nodes per element of a basis of `order`: (n + 1)², (n + 1)³ or (n + 1)(n + 2)/2.
    pub fn nodes(self, order: usize) -> usize {
        match self {
            Self::Quadrilateral => (order + 1).pow(2),
            Self::Hexahedron => (order + 1).pow(3),
            Self::Triangle => (order + 1) * (order + 2) / 2,
            Self::Tetrahedron => (order + 1) * (order + 2) * (order + 3) / 6,
        }
    }

    /// How far reference point `r` (its first [`Shape::dim`] entries) lies outside the
    /// reference element, in reference units, negative inside: the largest of −ξ, ξ − 1, … for
    /// the square and cube, of −ξ, −η, ξ + η − 1 (the barycentric coordinates negated) for the
    /// triangle. Twin of `spectral_outside` (spectral_element.glsl), which decides which
    /// fragments an element keeps.
    pub fn outside(self, r: &[f64]) -> f64 {
        let d = self.dim() as usize;
        let low = r[..d].iter().fold(f64::NEG_INFINITY, |m, &c| m.max(-c));
        match self {
            Self::Triangle => low.max(r[0] + r[1] - 1.0),
            Self::Tetrahedron => low.max(r[0] + r[1] + r[2] - 1.0),
            _ => r[..d].iter().fold(low, |m, &c| m.max(c - 1.0)),
        }
    }

    /// The point of the reference element nearest-ish `r` that values are taken at once a
    /// fragment is accepted (within the inside tolerance): each coordinate into [0, 1], and on
    /// the triangle ξ + η (the tetrahedron ξ + η + ζ) scaled back to 1. Twin of `spectral_clamp` (spectral_element.glsl).
    pub fn clamp<const D: usize>(self, r: [f64; D]) -> [f64; D] {
        let mut c = r.map(|x| x.clamp(0.0, 1.0));
        let d = (self.dim() as usize).min(D);
        let s: f64 = c[..d].iter().sum();
        if self.is_simplex() && s > 1.0 {
            for x in c.iter_mut().take(d) {
                *x /= s;
            }
        }
        c
    }
}

/// Spectral elements (quadrilaterals in the plane or in 3D, or hexahedra) with their fields.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralMesh {
    /// The elements' reference shape.
    pub shape: Shape,
    /// The geometry's basis (its order may be lower than the field's).
    pub geometry: Basis1d,
    /// The fields' basis.
    pub basis: Basis1d,
    /// Geometry control points: elements × (g + 1)², node (i, j) at `e (g+1)² + j (g+1) + i`.
    pub points: Vec<[f64; 3]>,
    /// The scalar fields.
    pub fields: Vec<Field>,
    /// Rational cells (VTK's Bézier cells with `RationalWeights`): a positive weight w per
    /// node, and then the geometry map is x = Σ w X B / Σ w B and every field f = Σ w F B / Σ w B
    /// (one basis for both; [`SpectralMesh::with_weights`]). `None`: polynomials.
    pub weights: Option<Vec<f64>>,
}

/// The rational value and derivatives N/W from a homogeneous sum (`n`, its derivatives `dn`)
/// and its weight sum (`w`, derivatives `dw`): (N/W)' = (N' − (N/W) W') / W.
pub(super) fn rational<const D: usize>(n: f64, dn: [f64; D], w: f64, dw: [f64; D]) -> (f64, [f64; D]) {
    let v = n / w;
    (v, std::array::from_fn(|a| (dn[a] - v * dw[a]) / w))
}

/// The axis-aligned box [lo, hi] of `points`.
pub fn bounds_of(points: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    points.iter().fold(([f64::MAX; 3], [f64::MIN; 3]), |(lo, hi), p| {
        (std::array::from_fn(|c| lo[c].min(p[c])), std::array::from_fn(|c| hi[c].max(p[c])))
    })
}

/// Whether `p` lies in the box of an element's control points grown by half its size on each
/// side (Lagrange geometry can bulge past its nodes a little), on the first `dims` axes.
fn near_box(points: &[[f64; 3]], p: &[f64], dims: usize) -> bool {
    let (lo, hi) = bounds_of(points);
    (0..dims).all(|c| {
        let grow = 0.5 * (hi[c] - lo[c]);
        p[c] >= lo[c] - grow && p[c] <= hi[c] + grow
    })
}

/// A Newton step of the inverse map at most half the reference element long per axis: far
/// from the solution a strongly curved (e.g. rational) map can send a full step out of the
/// basin; near it steps are tiny and Newton's quadratic convergence is kept.
pub(super) fn damped<const D: usize>(s: [f64; D]) -> [f64; D] {
    let longest = s.iter().fold(0.0f64, |a, c| a.max(c.abs()));
    if longest > 0.5 {
        s.map(|c| c * 0.5 / longest)
    } else {
        s
    }
}

/// Newton iterations of the inverse map: quadratic convergence from a guess inside the
/// element takes 3–6 steps for the curved meshes here; the cap only stops divergence.
pub const NEWTON_ITERATIONS: usize = 12;

impl SpectralMesh {
    /// Checks and assembles a data set: array lengths, finite values, and a geometry map that
    /// neither folds nor collapses (the Jacobian determinant keeps one sign on a (2g + 2)²
    /// sample grid; planar meshes only). Errors name the element or field.
    pub fn new(
        shape: Shape,
        geometry: Basis1d,
        basis: Basis1d,
        points: Vec<[f64; 3]>,
        fields: Vec<Field>,
    ) -> Result<Self, SpectralError> {
        let gm = shape.nodes(geometry.order);
        if points.is_empty() || !points.len().is_multiple_of(gm) {
            return Err(SpectralError::Length {
                what: format!("geometry points (order {} has {gm} per element)", geometry.order),
                found: points.len(),
                expected: (points.len() / gm).max(1) * gm,
            });
        }
        let elements = points.len() / gm;
        for (k, p) in points.iter().enumerate() {
            if p.iter().any(|c| !c.is_finite()) {
                return Err(SpectralError::NotFinite {
                    element: k / gm,
                    what: format!("geometry node {}", k % gm),
                });
            }
        }
        let fm = shape.nodes(basis.order);
        for f in &fields {
            if f.steps.is_empty() || f.steps.len() != f.times.len() {
                return Err(SpectralError::Length {
                    what: format!("field {:?}: time steps", f.name),
                    found: f.steps.len(),
                    expected: f.times.len().max(1),
                });
            }
            for (s, v) in f.steps.iter().enumerate() {
                if v.len() != elements * fm {
                    return Err(SpectralError::Length {
                        what: format!("field {:?} step {s}", f.name),
                        found: v.len(),
                        expected: elements * fm,
                    });
                }
                if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                    return Err(SpectralError::NotFinite {
                        element: k / fm,
                        what: format!("field {:?} step {s} value {}", f.name, k % fm),
                    });
                }
            }
        }
        let mesh = Self { shape, geometry, basis, points, fields, weights: None };
        mesh.check_orientations()?;
        Ok(mesh)
    }

    /// The mesh made rational by `weights`, one per geometry node (VTK's `RationalWeights`):
    /// each must be positive and finite (so Σ w B > 0 everywhere and the element lies in its
    /// control points' convex hull), the geometry and fields must share one Bernstein basis, and
    /// the rational map must neither fold nor collapse. Errors name the element.
    pub fn with_weights(mut self, weights: Vec<f64>) -> Result<Self, SpectralError> {
        if weights.len() != self.points.len() {
            return Err(SpectralError::Length {
                what: "rational weights (one per geometry node)".into(),
                found: weights.len(),
                expected: self.points.len(),
            });
        }
        if self.shape.is_simplex() {
            return Err(SpectralError::Missing(
                "rational weights are read for Bézier quadrilaterals and hexahedra only".into(),
            ));
        }
        if self.geometry != self.basis || self.geometry.set != super::basis::NodeSet::Bernstein {
            return Err(SpectralError::Missing(
                "rational weights need the geometry and the fields on one Bernstein basis".into(),
            ));
        }
        let gm = self.points_per_element();
        if let Some(k) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(SpectralError::Invalid {
                element: k / gm,
                what: format!(
                    "rational weight {} of node {} (weights must be positive and finite)",
                    weights[k],
                    k % gm
                ),
            });
        }
        self.weights = Some(weights);
        self.check_orientations()?;
        Ok(self)
    }

    /// Element `e`'s rational weights (one per geometry node), when the mesh is rational.
    pub fn element_weights(&self, e: usize) -> Option<&[f64]> {
        let gm = self.points_per_element();
        self.weights.as_deref().map(|w| &w[e * gm..(e + 1) * gm])
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.points.len() / self.points_per_element()
    }

    /// The box [lo, hi] of every geometry point.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        bounds_of(&self.points)
    }

    /// The length of the diagonal of [`SpectralMesh::bounds`]: the mesh's size.
    pub fn diagonal(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt()
    }

    /// Whether this is a quadrilateral or triangle mesh with z = 0 at every geometry point
    /// (drawn in 2D).
    pub fn is_planar(&self) -> bool {
        !self.shape.is_volume() && self.points.iter().all(|p| p[2] == 0.0)
    }

    /// Geometry points per element.
    pub fn points_per_element(&self) -> usize {
        self.shape.nodes(self.geometry.order)
    }

    /// Field coefficients per element.
    pub fn values_per_element(&self) -> usize {
        self.shape.nodes(self.basis.order)
    }

    /// The geometry points of element `e`.
    pub fn element_points(&self, e: usize) -> &[[f64; 3]] {
        let gm = self.points_per_element();
        &self.points[e * gm..(e + 1) * gm]
    }

    /// The field index of `name`, or the first field when `None`.
    pub fn field_index(&self, name: Option<&str>) -> Result<usize, SpectralError> {
        match name {
            None if !self.fields.is_empty() => Ok(0),
            None => Err(SpectralError::Missing("the data set has no fields".into())),
            Some(n) => self.fields.iter().position(|f| f.name == n).ok_or_else(|| {
                let names: Vec<&str> = self.fields.iter().map(|f| f.name.as_str()).collect();
                SpectralError::Missing(format!("no field {n:?}; the fields are {names:?}"))
            }),
        }
    }

    /// The coefficients of element `e` for `field` at `step`.
    pub fn element_values(&self, field: usize, step: usize, e: usize) -> &[f64] {
        let fm = self.values_per_element();
        &self.fields[field].steps[step][e * fm..(e + 1) * fm]
    }

    /// The geometry map of quadrilateral or triangle `e` at (ξ, η): the point and its
    /// derivatives ∂x/∂ξ, ∂x/∂η. Twin of `spectral_map` (spectral_element.glsl) and, for
    /// triangles, `simplex_triangle_map` (spectral_simplex.glsl).
    pub fn map(&self, e: usize, xi: f64, eta: f64) -> ([f64; 3], [[f64; 3]; 2]) {
        if self.shape == Shape::Triangle {
            let pts = self.element_points(e);
            let (mut x, mut dx, mut dy) = ([0.0; 3], [0.0; 3], [0.0; 3]);
            super::simplex::triangle_terms(self.geometry.order, [xi, eta], |k, l, [lx, ly]| {
                for c in 0..3 {
                    x[c] += l * pts[k][c];
                    dx[c] += lx * pts[k][c];
                    dy[c] += ly * pts[k][c];
                }
            });
            return (x, [dx, dy]);
        }
        let m = self.geometry.len();
        let (mut a, mut da, mut b, mut db) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
        self.geometry.eval(xi, &mut a, Some(&mut da));
        self.geometry.eval(eta, &mut b, Some(&mut db));
        let pts = self.element_points(e);
        let weights = self.element_weights(e);
        let (mut x, mut dx, mut dy) = ([0.0; 3], [0.0; 3], [0.0; 3]);
        let (mut w, mut dw) = (0.0, [0.0; 2]);
        for j in 0..m {
            for i in 0..m {
                let p = pts[j * m + i];
                // Homogeneous sums (w = 1 and no division for polynomial meshes).
                let wk = weights.map_or(1.0, |w| w[j * m + i]);
                for c in 0..3 {
                    x[c] += a[i] * b[j] * wk * p[c];
                    dx[c] += da[i] * b[j] * wk * p[c];
                    dy[c] += a[i] * db[j] * wk * p[c];
                }
                w += a[i] * b[j] * wk;
                dw[0] += da[i] * b[j] * wk;
                dw[1] += a[i] * db[j] * wk;
            }
        }
        if weights.is_none() {
            return (x, [dx, dy]);
        }
        let per: [(f64, [f64; 2]); 3] = std::array::from_fn(|c| rational(x[c], [dx[c], dy[c]], w, dw));
        (per.map(|p| p.0), [per.map(|p| p.1[0]), per.map(|p| p.1[1])])
    }

    /// The value of `field` at `step` in quadrilateral or triangle `e` at reference point
    /// (ξ, η).
    pub fn value(&self, field: usize, step: usize, e: usize, xi: f64, eta: f64) -> f64 {
        if self.shape == Shape::Triangle {
            let v = self.element_values(field, step, e);
            let mut sum = 0.0;
            super::simplex::triangle_terms(self.basis.order, [xi, eta], |k, l, _| sum += l * v[k]);
            return sum;
        }
        let m = self.basis.len();
        let (mut a, mut b) = ([0.0; 16], [0.0; 16]);
        self.basis.eval(xi, &mut a, None);
        self.basis.eval(eta, &mut b, None);
        let v = self.element_values(field, step, e);
        match self.element_weights(e) {
            None => (0..m).map(|j| b[j] * (0..m).map(|i| a[i] * v[j * m + i]).sum::<f64>()).sum(),
            Some(w) => {
                let (mut n, mut d) = (0.0, 0.0);
                for j in 0..m {
                    for i in 0..m {
                        n += a[i] * b[j] * w[j * m + i] * v[j * m + i];
                        d += a[i] * b[j] * w[j * m + i];
                    }
                }
                n / d
            }
        }
    }

    /// The reference point of element `e` that maps to the planar point `p`, by Newton's
    /// method in f64 from `guess`: `None` when it does not converge (p far outside).
    pub fn inverse_map(&self, e: usize, p: [f64; 2], guess: [f64; 2]) -> Option<[f64; 2]> {
        let mut r = guess;
        for _ in 0..4 * NEWTON_ITERATIONS {
            let (x, [dx, dy]) = self.map(e, r[0], r[1]);
            let (fx, fy) = (x[0] - p[0], x[1] - p[1]);
            let det = dx[0] * dy[1] - dy[0] * dx[1];
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let s = damped([(dy[1] * fx - dy[0] * fy) / det, (-dx[1] * fx + dx[0] * fy) / det]);
            r = [r[0] - s[0], r[1] - s[1]];
            if r.iter().any(|c| !c.is_finite() || c.abs() > 10.0) {
                return None;
            }
            if s[0].abs().max(s[1].abs()) < 1e-14 {
                return Some(r);
            }
        }
        let (x, _) = self.map(e, r[0], r[1]);
        ((x[0] - p[0]).hypot(x[1] - p[1]) < 1e-12 * (1.0 + p[0].abs() + p[1].abs())).then_some(r)
    }

    /// The element of a planar mesh containing `p` and its reference point (the first one, in
    /// element order, whose inverse map lands within `tol` of the reference square or
    /// triangle, [`Shape::outside`]), searching only elements
    /// whose bounding box (grown by `tol` of its size) contains `p`.
    pub fn locate(&self, p: [f64; 2], tol: f64) -> Option<(usize, [f64; 2])> {
        (0..self.elements()).find_map(|e| {
            if !near_box(self.element_points(e), &p, 2) {
                return None;
            }
            let guess = if self.shape == Shape::Triangle { [1.0 / 3.0; 2] } else { [0.5; 2] };
            let r = self.inverse_map(e, p, guess)?;
            (self.shape.outside(&r) <= tol).then_some((e, r))
        })
    }

    /// The least and greatest value of `field` at `step`, sampled on a (2n + 1)² grid per
    /// element (the colour range's "auto").
    pub fn value_range(&self, field: usize, step: usize) -> (f64, f64) {
        let mut range = (f64::MAX, f64::MIN);
        self.for_each_sample(|e, r| {
            let v = match self.shape {
                Shape::Quadrilateral | Shape::Triangle => self.value(field, step, e, r[0], r[1]),
                Shape::Hexahedron | Shape::Tetrahedron => self.value_hex(field, step, e, r),
            };
            range = (range.0.min(v), range.1.max(v));
        });
        range
    }

    /// Calls `visit(e, r)` at the points of a (2n + 1)ᴰ grid on every element's reference
    /// square or cube, or of the grid's half with ξ + η ≤ 1 on a triangle (n the fields'
    /// order; r's third coordinate 0 in 2D): where colour ranges are sampled.
    pub fn for_each_sample(&self, mut visit: impl FnMut(usize, [f64; 3])) {
        let s = 2 * self.basis.order.max(1);
        let layers = if self.shape.is_volume() { s } else { 0 };
        for e in 0..self.elements() {
            for k in 0..=layers {
                // Simplices: the grid's points with Σ r ≤ 1.
                let rows = if self.shape == Shape::Tetrahedron { s - k } else { s };
                for j in 0..=rows {
                    let row = if self.shape.is_simplex() { rows - j } else { s };
                    for i in 0..=row {
                        visit(e, [i, j, k].map(|c| c as f64 / s as f64));
                    }
                }
            }
        }
    }

    /// The geometry map of hexahedron or tetrahedron `e` at r = (ξ, η, ζ): the point and its
    /// derivatives along ξ, η and ζ.
    pub fn map_hex(&self, e: usize, r: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        if self.shape == Shape::Tetrahedron {
            let pts = self.element_points(e);
            let (mut x, mut d) = ([0.0; 3], [[0.0; 3]; 3]);
            super::simplex::tetra_terms(self.geometry.order, r, |k, l, dl| {
                for c in 0..3 {
                    x[c] += l * pts[k][c];
                    for a in 0..3 {
                        d[a][c] += dl[a] * pts[k][c];
                    }
                }
            });
            return (x, d);
        }
        debug_assert_eq!(self.shape, Shape::Hexahedron);
        let m = self.geometry.len();
        let mut v = [[0.0; 16]; 3];
        let mut d = [[0.0; 16]; 3];
        for a in 0..3 {
            self.geometry.eval(r[a], &mut v[a], Some(&mut d[a]));
        }
        let pts = self.element_points(e);
        let weights = self.element_weights(e);
        let (mut x, mut j) = ([0.0; 3], [[0.0; 3]; 3]);
        let (mut ws, mut dws) = (0.0, [0.0; 3]);
        for k in 0..m {
            for jj in 0..m {
                for i in 0..m {
                    let p = pts[(k * m + jj) * m + i];
                    let wk = weights.map_or(1.0, |w| w[(k * m + jj) * m + i]);
                    let w = [
                        v[0][i] * v[1][jj] * v[2][k] * wk,
                        d[0][i] * v[1][jj] * v[2][k] * wk,
                        v[0][i] * d[1][jj] * v[2][k] * wk,
                        v[0][i] * v[1][jj] * d[2][k] * wk,
                    ];
                    for c in 0..3 {
                        x[c] += w[0] * p[c];
                        j[0][c] += w[1] * p[c];
                        j[1][c] += w[2] * p[c];
                        j[2][c] += w[3] * p[c];
                    }
                    ws += w[0];
                    for a in 0..3 {
                        dws[a] += w[a + 1];
                    }
                }
            }
        }
        if weights.is_none() {
            return (x, j);
        }
        let per: [(f64, [f64; 3]); 3] =
            std::array::from_fn(|c| rational(x[c], [j[0][c], j[1][c], j[2][c]], ws, dws));
        (per.map(|p| p.0), std::array::from_fn(|a| per.map(|p| p.1[a])))
    }

    /// The value of `field` at `step` in hexahedron or tetrahedron `e` at r = (ξ, η, ζ).
    pub fn value_hex(&self, field: usize, step: usize, e: usize, r: [f64; 3]) -> f64 {
        if self.shape == Shape::Tetrahedron {
            let v = self.element_values(field, step, e);
            let mut sum = 0.0;
            super::simplex::tetra_terms(self.basis.order, r, |k, l, _| sum += l * v[k]);
            return sum;
        }
        let m = self.basis.len();
        let mut v = [[0.0; 16]; 3];
        for a in 0..3 {
            self.basis.eval(r[a], &mut v[a], None);
        }
        let f = self.element_values(field, step, e);
        let weights = self.element_weights(e);
        let (mut sum, mut ws) = (0.0, 0.0);
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let node = (k * m + j) * m + i;
                    let b = v[0][i] * v[1][j] * v[2][k];
                    match weights {
                        None => sum += b * f[node],
                        Some(w) => {
                            sum += b * w[node] * f[node];
                            ws += b * w[node];
                        }
                    }
                }
            }
        }
        if weights.is_some() {
            sum / ws
        } else {
            sum
        }
    }

    /// The reference point of hexahedron or tetrahedron `e` that maps to `p`, by Newton's method in f64 from
    /// `guess`: `None` when it does not converge.
    pub fn inverse_map_hex(&self, e: usize, p: [f64; 3], guess: [f64; 3]) -> Option<[f64; 3]> {
        let mut r = guess;
        for _ in 0..4 * NEWTON_ITERATIONS {
            let (x, j) = self.map_hex(e, r);
            let f = [x[0] - p[0], x[1] - p[1], x[2] - p[2]];
            // Solve J s = f with J's columns j[0], j[1], j[2] (Cramer's rule).
            let det3 = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
                a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1])
                    + c[0] * (a[1] * b[2] - a[2] * b[1])
            };
            let det = det3(j[0], j[1], j[2]);
            if det == 0.0 || !det.is_finite() {
                return None;
            }
            let s = damped([det3(f, j[1], j[2]) / det, det3(j[0], f, j[2]) / det, det3(j[0], j[1], f) / det]);
            r = [r[0] - s[0], r[1] - s[1], r[2] - s[2]];
            if r.iter().any(|c| !c.is_finite() || c.abs() > 10.0) {
                return None;
            }
            if s.iter().fold(0.0f64, |a, c| a.max(c.abs())) < 1e-14 {
                return Some(r);
            }
        }
        let (x, _) = self.map_hex(e, r);
        let scale = 1.0 + p.iter().fold(0.0f64, |a, c| a.max(c.abs()));
        ((0..3).map(|c| (x[c] - p[c]).powi(2)).sum::<f64>().sqrt() < 1e-12 * scale).then_some(r)
    }

    /// The hexahedron or tetrahedron containing `p` and its reference point (the first, in
    /// element order, whose inverse map lands within `tol` of the reference element), searching only elements whose control-point
    /// box (grown by half its size) contains `p`.
    pub fn locate_hex(&self, p: [f64; 3], tol: f64) -> Option<(usize, [f64; 3])> {
        (0..self.elements()).find_map(|e| {
            if !near_box(self.element_points(e), &p, 3) {
                return None;
            }
            let guess = if self.shape == Shape::Tetrahedron { [0.25; 3] } else { [0.5; 3] };
            let r = self.inverse_map_hex(e, p, guess)?;
            (self.shape.outside(&r) <= tol).then_some((e, r))
        })
    }

    fn check_orientation_hex(&self, e: usize) -> Result<(), SpectralError> {
        let s = 2 * self.geometry.order + 1;
        let mut sign = 0.0;
        let tetra = self.shape == Shape::Tetrahedron;
        for k in 0..=s {
            for j in 0..=(if tetra { s - k } else { s }) {
                for i in 0..=(if tetra { s - k - j } else { s }) {
                    let r = [i, j, k].map(|c| c as f64 / s as f64);
                    let (_, d) = self.map_hex(e, r);
                    let det = d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1])
                        - d[1][0] * (d[0][1] * d[2][2] - d[0][2] * d[2][1])
                        + d[2][0] * (d[0][1] * d[1][2] - d[0][2] * d[1][1]);
                    if det == 0.0 || (sign != 0.0 && det.signum() != sign) {
                        return Err(SpectralError::Invalid {
                            element: e,
                            what: format!(
                                "the geometry map folds or collapses (Jacobian determinant {det:e} at ξ = {:.3}, η = {:.3}, ζ = {:.3})",
                                r[0], r[1], r[2]
                            ),
                        });
                    }
                    sign = det.signum();
                }
            }
        }
        Ok(())
    }

    /// Every element's map keeps one orientation (planar quadrilaterals and hexahedra; surfaces
    /// in 3D have no sign to keep).
    fn check_orientations(&self) -> Result<(), SpectralError> {
        for e in 0..self.elements() {
            match self.shape {
                Shape::Quadrilateral | Shape::Triangle if self.is_planar() => self.check_orientation(e)?,
                Shape::Hexahedron | Shape::Tetrahedron => self.check_orientation_hex(e)?,
                Shape::Quadrilateral | Shape::Triangle => {}
            }
        }
        Ok(())
    }

    fn check_orientation(&self, e: usize) -> Result<(), SpectralError> {
        let s = 2 * self.geometry.order + 1;
        let mut sign = 0.0;
        for j in 0..=s {
            let row = if self.shape == Shape::Triangle { s - j } else { s };
            for i in 0..=row {
                let (_, [dx, dy]) = self.map(e, i as f64 / s as f64, j as f64 / s as f64);
                let det = dx[0] * dy[1] - dy[0] * dx[1];
                if det == 0.0 || (sign != 0.0 && det.signum() != sign) {
                    return Err(SpectralError::Invalid {
                        element: e,
                        what: format!(
                            "the geometry map folds or collapses (Jacobian determinant {det:e} at ξ = {:.3}, η = {:.3})",
                            i as f64 / s as f64,
                            j as f64 / s as f64
                        ),
                    });
                }
                sign = det.signum();
            }
        }
        Ok(())
    }
}
