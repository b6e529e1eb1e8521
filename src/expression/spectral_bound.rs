//! The rounding bound of a derived field on a spectral element: how far the device's f32
//! evaluation may lie from the f64 reference ([`DerivedField::value_at`]), for the per-pixel
//! tests.

use super::spectral::{geometry, gradient, DerivedField};
use super::{InputErrors, Inputs};
use crate::spectral::basis::Basis1d;
use crate::spectral::reference::{rounding_bound as value_bound, rounding_bound_hex as value_bound_hex};
use crate::spectral::simplex::{tetra_terms, triangle_terms};
use crate::spectral::{Shape, SpectralMesh};

/// The multi-index of node `k` of a tensor-product element with `m` nodes per axis.
fn multi_index<const D: usize>(k: usize, m: usize) -> [usize; D] {
    std::array::from_fn(|a| (k / m.pow(a as u32)) % m)
}

/// Π_a b_a[i_a] and its derivative along each axis, from 1D values `b` and derivatives `db`.
fn tensor<const D: usize>(b: &[[f64; 16]; D], db: &[[f64; 16]; D], index: [usize; D]) -> (f64, [f64; D]) {
    let value = (0..D).map(|a| b[a][index[a]]).product();
    let derivative = std::array::from_fn(|a| {
        (0..D).map(|c| if c == a { db[c][index[c]] } else { b[c][index[c]] }).product()
    });
    (value, derivative)
}

/// Every node's basis function of `basis` (the geometry's or the fields') at r and its
/// derivatives along each reference axis, in node order: Silvester's basis on triangles and
/// tetrahedra ([`crate::spectral::simplex::triangle_terms`], `tetra_terms`), tensor products
/// of the 1D basis otherwise.
fn node_terms<const D: usize>(mesh: &SpectralMesh, basis: &Basis1d, r: [f64; D]) -> Vec<(f64, [f64; D])> {
    let n = basis.order;
    let mut out = vec![(0.0, [0.0; D]); mesh.shape.nodes(n)];
    match mesh.shape {
        Shape::Triangle => triangle_terms(n, [r[0], r[1.min(D - 1)]], |k, l, dl| {
            out[k] = (l, std::array::from_fn(|a| dl[a.min(1)]));
        }),
        Shape::Tetrahedron => tetra_terms(n, std::array::from_fn(|a| r[a.min(D - 1)]), |k, l, dl| {
            out[k] = (l, std::array::from_fn(|a| dl[a.min(2)]));
        }),
        Shape::Quadrilateral | Shape::Hexahedron => {
            let (mut b, mut db) = ([[0.0; 16]; D], [[0.0; 16]; D]);
            for a in 0..D {
                basis.eval(r[a], &mut b[a], Some(&mut db[a]));
            }
            for (k, term) in out.iter_mut().enumerate() {
                *term = tensor(&b, &db, multi_index::<D>(k, basis.len()));
            }
        }
    }
    out
}

impl DerivedField {
    /// A bound on |device − exact| of the derived value at reference point `r` of
    /// quadrilateral `e` ([`crate::expression::Expression::rounding_bound`]) from bounds on what
    /// it reads, each times 4 as [`crate::spectral::reference::rounding_bound`]:
    /// - a value: that function's bound (its f32 sum and the f32 reference point);
    /// - a gradient g = J⁺ d: ‖J⁺‖ e_d (the derivative sum's rounding, c m ε Σ_a |∂_a(ℓ…ℓ) F|),
    ///   ‖J⁺‖ ‖g‖ e_J (the tangents' rounding, c(g + 1) ε Σ_a |∂_a(γ…γ)| |X|), 8 κ(J)² ε ‖g‖
    ///   (the metric or inverse in f32), and the gradient's change over the reference-point
    ///   error δr = ‖J⁺‖ · position (central differences in f64);
    /// - the point: position = (2|x| + c(g + 1) Σ|γ…γ X|) ε,
    ///
    /// with c = 8 on quadrilaterals and triangles (Silvester's basis summed as a quadrilateral's
    /// of m = n + 1, as [`crate::spectral::reference::rounding_bound`]). Polynomial cells (rational ones carry weights in every
    /// sum; not derived here: the bound is then an estimate).
    pub fn rounding_bound(
        &self,
        mesh: &SpectralMesh,
        shown: usize,
        step: usize,
        e: usize,
        r: [f64; 2],
    ) -> f64 {
        self.bound_n(mesh, shown, step, e, r)
    }

    /// [`Self::rounding_bound`] on hexahedron or tetrahedron `e` at r = (ξ, η, ζ), with c = 12 and the point
    /// on the cut plane interpolated across the drawn rectangle (64|x| ε instead of 2|x| ε, as
    /// [`crate::spectral::reference::rounding_bound_hex`]).
    pub fn rounding_bound_hex(
        &self,
        mesh: &SpectralMesh,
        shown: usize,
        step: usize,
        e: usize,
        r: [f64; 3],
    ) -> f64 {
        self.bound_n(mesh, shown, step, e, r)
    }

    fn bound_n<const D: usize>(
        &self,
        mesh: &SpectralMesh,
        shown: usize,
        step: usize,
        e: usize,
        r: [f64; D],
    ) -> f64 {
        let eps = f64::from(f32::EPSILON);
        let (c, point_factor) = if D == 3 { (12.0, 64.0) } else { (8.0, 2.0) };
        let (m, gm) = (mesh.basis.len(), mesh.geometry.len());
        let field_terms = node_terms(mesh, &mesh.basis, r);
        let geometry_terms = node_terms(mesh, &mesh.geometry, r);
        let (point, tangents) = geometry(mesh, e, r);
        let (mut sum_x, mut sum_j) = (0.0, 0.0);
        for (p, &(value, derivative)) in mesh.element_points(e).iter().zip(&geometry_terms) {
            let size = p.iter().fold(0.0f64, |s, c| s.max(c.abs()));
            sum_x += value.abs() * size;
            sum_j += derivative.iter().map(|d| d.abs()).sum::<f64>() * size;
        }
        let xmax = point.iter().fold(0.0f64, |s, c| s.max(c.abs()));
        let position = (point_factor * xmax + c * gm as f64 * sum_x) * eps;
        // The metric G = JᵀJ: ‖J⁺‖ ≤ √trace(G⁻¹), ‖J‖ ≤ √trace(G).
        let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let trace: f64 = tangents.iter().map(|t| dot(*t, *t)).sum();
        let inverse_trace = if D == 3 {
            let j = glam::DMat3::from_cols(tangents[0].into(), tangents[1].into(), tangents[2].into());
            let inv = (j.transpose() * j).inverse();
            inv.x_axis.x + inv.y_axis.y + inv.z_axis.z
        } else {
            let (g11, g12, g22) =
                (dot(tangents[0], tangents[0]), dot(tangents[0], tangents[1]), dot(tangents[1], tangents[1]));
            (g11 + g22) / (g11 * g22 - g12 * g12)
        };
        let pinv = inverse_trace.sqrt();
        let kappa = trace.sqrt() * pinv;
        let e_tangent = c * gm as f64 * eps * sum_j;
        let dr = pinv * position;
        let fields = self.fields(shown);
        let (mut values, mut gradients) = (Vec::new(), Vec::new());
        let (mut value_errors, mut gradient_errors) = (Vec::new(), Vec::new());
        let gradient_at = |f: usize, r: [f64; D]| {
            let (_, t) = geometry(mesh, e, r);
            gradient(&t, &mesh.value_gradient_at(f, step, e, r).1)
        };
        for f in fields {
            let (v, d) = mesh.value_gradient_at(f, step, e, r);
            let grad = gradient(&tangents, &d);
            let mut sum_d = 0.0;
            for (coefficient, (_, derivative)) in mesh.element_values(f, step, e).iter().zip(&field_terms) {
                sum_d += derivative.iter().map(|d| d.abs()).sum::<f64>() * coefficient.abs();
            }
            let gnorm = dot(grad, grad).sqrt();
            let h = 1e-6;
            let mut change = 0.0f64;
            for axis in 0..D {
                let (mut lo, mut hi) = (r, r);
                lo[axis] = (r[axis] - h).max(0.0);
                hi[axis] = (r[axis] + h).min(1.0);
                let (gl, gh) = (gradient_at(f, lo), gradient_at(f, hi));
                let diff = [gh[0] - gl[0], gh[1] - gl[1], gh[2] - gl[2]];
                change += dot(diff, diff).sqrt() / (hi[axis] - lo[axis]);
            }
            let e_d = c * m as f64 * eps * sum_d;
            values.push(v);
            gradients.push(grad);
            value_errors.push(if D == 3 {
                value_bound_hex(mesh, f, step, e, [r[0], r[1], r[2]])
            } else {
                value_bound(mesh, f, step, e, [r[0], r[1]])
            });
            gradient_errors.push(
                4.0 * (pinv * e_d
                    + pinv * gnorm * e_tangent
                    + 8.0 * kappa * kappa * eps * gnorm
                    + change * dr),
            );
        }
        let time = Self::time(mesh, shown, step);
        let variables = Self::variables(point, time);
        let inputs = Inputs { values: &values, gradients: &gradients, variables: &variables };
        let p = 4.0 * position;
        let errors = InputErrors {
            values: &value_errors,
            gradients: &gradient_errors,
            variables: &[p, p, p, eps * time.abs()],
        };
        self.expression.rounding_bound(&inputs, &errors)
    }
}
