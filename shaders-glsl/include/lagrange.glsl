// One-dimensional bases of the tensor-product spectral element on [0, 1] (seed 002): Lagrange
// polynomials in the first barycentric form, l_j(x) = w_j prod_{k != j} (x - x_k), formed by
// prefix and suffix products (no division, exact at the nodes; backward stable, Higham 2004),
// and the Bernstein polynomials by the de Casteljau triangle.
// Twin of src/spectral/basis.rs (Basis1d::eval); tests/spectral.rs checks they agree.
#ifndef GALERKIN_LAGRANGE_GLSL
#define GALERKIN_LAGRANGE_GLSL

// MAX_ORDER + 1 of basis.rs.
#define SPECTRAL_MAX_NODES 13
#define SPECTRAL_LAGRANGE 0u
#define SPECTRAL_BERNSTEIN 1u

// The n + 1 basis values at x (and their derivatives when want_derivatives) of the basis of
// `kind` (SPECTRAL_LAGRANGE with `nodes` and barycentric `weights`, or SPECTRAL_BERNSTEIN) and
// order n. The renderer passes specialization constants, so the loops unroll and the nodes fold.
void spectral_basis_eval(uint kind, uint order, float nodes[SPECTRAL_MAX_NODES], float weights[SPECTRAL_MAX_NODES],
                         float x, bool want_derivatives,
                         out float values[SPECTRAL_MAX_NODES], out float derivatives[SPECTRAL_MAX_NODES]) {
    uint m = order + 1u;
    for (uint i = 0u; i < SPECTRAL_MAX_NODES; ++i) { values[i] = 0.0; derivatives[i] = 0.0; }
    if (kind == SPECTRAL_BERNSTEIN) {
        uint n = order;
        values[0] = 1.0;
        for (uint r = 1u; r <= n; ++r) {
            if (r == n && want_derivatives) {
                for (uint i = 0u; i <= n; ++i) {
                    float left = i > 0u ? values[i - 1u] : 0.0;
                    float right = i < n ? values[i] : 0.0;
                    derivatives[i] = float(n) * (left - right);
                }
            }
            values[r] = x * values[r - 1u];
            for (uint t = 1u; t < r; ++t) {
                uint i = r - t;  // i = r - 1, ..., 1, counted upwards (see the suffix loop)
                values[i] = (1.0 - x) * values[i] + x * values[i - 1u];
            }
            values[0] *= 1.0 - x;
        }
        return;
    }
    float prefix[SPECTRAL_MAX_NODES + 1];
    float dprefix[SPECTRAL_MAX_NODES + 1];
    float suffix[SPECTRAL_MAX_NODES + 1];
    float dsuffix[SPECTRAL_MAX_NODES + 1];
    prefix[0] = 1.0;
    dprefix[0] = 0.0;
    for (uint k = 0u; k < m; ++k) {
        float d = x - nodes[k];
        dprefix[k + 1u] = dprefix[k] * d + prefix[k];
        prefix[k + 1u] = prefix[k] * d;
    }
    suffix[m] = 1.0;
    dsuffix[m] = 0.0;
    // Counted upwards: a loop the drivers recognise and unroll (k = m - 1, ..., 0).
    for (uint t = 0u; t < m; ++t) {
        uint k = m - 1u - t;
        float d = x - nodes[k];
        dsuffix[k] = dsuffix[k + 1u] * d + suffix[k + 1u];
        suffix[k] = suffix[k + 1u] * d;
    }
    for (uint j = 0u; j < m; ++j) {
        values[j] = weights[j] * prefix[j] * suffix[j + 1u];
        if (want_derivatives) derivatives[j] = weights[j] * (dprefix[j] * suffix[j + 1u] + prefix[j] * dsuffix[j + 1u]);
    }
}

#endif
