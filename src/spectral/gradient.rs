//! A field's derivatives in reference coordinates — what derived fields (`--expr`'s `grad`)
//! turn into physical gradients with the geometry map's Jacobian.

use super::mesh::{rational, SpectralMesh};

impl SpectralMesh {
    /// The value of `field` at `step` in element `e` at reference point `r` and its
    /// derivatives along each reference axis (quotient rule on rational cells): D = 2 for
    /// quadrilaterals (node (i, j) at j(n+1) + i) and triangles, 3 for hexahedra (node
    /// (i, j, k) at (k(n+1) + j)(n+1) + i) and tetrahedra. Twin of `spectral_slot_value_gradient` and
    /// `spectral_slot_value_gradient_hex` (spectral_element.glsl).
    pub fn value_gradient_at<const D: usize>(
        &self,
        field: usize,
        step: usize,
        e: usize,
        r: [f64; D],
    ) -> (f64, [f64; D]) {
        if self.shape == super::mesh::Shape::Tetrahedron {
            // Silvester's basis (node (i, j, k) at simplex::tetra_index), D = 3.
            let f = self.element_values(field, step, e);
            let (mut v, mut dv) = (0.0, [0.0; D]);
            super::simplex::tetra_terms(
                self.basis.order,
                std::array::from_fn(|a| r[a.min(D - 1)]),
                |k, l, dl| {
                    v += l * f[k];
                    for a in 0..D.min(3) {
                        dv[a] += dl[a] * f[k];
                    }
                },
            );
            return (v, dv);
        }
        if self.shape == super::mesh::Shape::Triangle {
            // Silvester's basis (node (i, j) at simplex::triangle_index), D = 2.
            let f = self.element_values(field, step, e);
            let (mut v, mut dv) = (0.0, [0.0; D]);
            super::simplex::triangle_terms(self.basis.order, [r[0], r[1]], |k, l, dl| {
                v += l * f[k];
                for a in 0..D.min(2) {
                    dv[a] += dl[a] * f[k];
                }
            });
            return (v, dv);
        }
        let m = self.basis.len();
        let mut v = [[0.0; 16]; D];
        let mut d = [[0.0; 16]; D];
        for a in 0..D {
            self.basis.eval(r[a], &mut v[a], Some(&mut d[a]));
        }
        let f = self.element_values(field, step, e);
        let weights = self.element_weights(e);
        let (mut n, mut dn, mut w, mut dw) = (0.0, [0.0; D], 0.0, [0.0; D]);
        for (node, &value) in f.iter().enumerate() {
            let index: [usize; D] = std::array::from_fn(|a| (node / m.pow(a as u32)) % m);
            let b: f64 = (0..D).map(|a| v[a][index[a]]).product();
            let wk = weights.map_or(1.0, |w| w[node]);
            n += b * wk * value;
            w += b * wk;
            for a in 0..D {
                let db: f64 = (0..D).map(|c| if c == a { d[c][index[c]] } else { v[c][index[c]] }).product();
                dn[a] += db * wk * value;
                dw[a] += db * wk;
            }
        }
        if weights.is_none() {
            return (n, dn);
        }
        rational(n, dn, w, dw)
    }

    /// [`Self::value_gradient_at`] on quadrilateral `e` at (ξ, η): (f, [f_ξ, f_η]).
    pub fn value_gradient(&self, field: usize, step: usize, e: usize, xi: f64, eta: f64) -> (f64, [f64; 2]) {
        self.value_gradient_at(field, step, e, [xi, eta])
    }
}
