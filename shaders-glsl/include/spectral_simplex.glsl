// Lagrange triangles and tetrahedra on the device (SPECTRAL_SIMPLEX): Silvester's basis
// L_ij(xi, eta) = R_i(xi) R_j(eta) R_{n-i-j}(1 - xi - eta), with R_k(l) = prod_{m<k} (n l - m)/(m + 1),
// evaluated as three rows of 1D factors, as a quadrilateral's basis is two 1D bases. Node (i, j)
// (i + j <= n) of element e at e N + j (n + 1) - j (j - 1)/2 + i, N = (n + 1)(n + 2)/2.
// Included by spectral_element.glsl after its buffers and coefficient layout.
// Twin of src/spectral/simplex.rs (silvester_row, triangle_terms) and the triangle branches of
// SpectralMesh::map, value and value_gradient_at.
#ifndef GALERKIN_SPECTRAL_SIMPLEX_GLSL
#define GALERKIN_SPECTRAL_SIMPLEX_GLSL

// v[k] = R_k(lambda) for k = 0..n (0 past n) and, when asked, d[k] = R_k'(lambda), by the
// recurrence R_k = R_{k-1} (n lambda - k + 1)/k. Twin of simplex::silvester_row.
void simplex_silvester(uint n, float lambda, bool want_derivatives, out float v[SPECTRAL_MAX_NODES],
                       out float d[SPECTRAL_MAX_NODES]) {
    v[0] = 1.0;
    d[0] = 0.0;
    for (uint k = 1u; k < SPECTRAL_MAX_NODES; ++k) {
        bool live = k <= n;
        float factor = (float(n) * lambda - float(k - 1u)) / float(k);
        d[k] = live && want_derivatives ? d[k - 1u] * factor + v[k - 1u] * float(n) / float(k) : 0.0;
        v[k] = live ? v[k - 1u] * factor : 0.0;
    }
}

// The geometry map x(xi, eta) of triangle e and its derivatives along xi and eta:
// dL/dxi = R_i' R_j R_l - R_i R_j R_l', dL/deta = R_i R_j' R_l - R_i R_j R_l' (l = n - i - j).
vec3 simplex_triangle_map(uint e, vec2 r, out vec3 dxi, out vec3 deta) {
    const uint n = SPECTRAL_GEOMETRY_ORDER;
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES];
    simplex_silvester(n, r.x, true, a, da);
    simplex_silvester(n, r.y, true, b, db);
    simplex_silvester(n, 1.0 - r.x - r.y, true, c, dc);
    uint k = e * ((n + 1u) * (n + 2u) / 2u);
    vec3 x = vec3(0.0);
    dxi = vec3(0.0);
    deta = vec3(0.0);
    for (uint j = 0u; j <= n; ++j) {
        // Per row: sum a_i c_l X, sum a_i' c_l X and sum a_i c_l' X.
        vec3 row = vec3(0.0), row_xi = vec3(0.0), row_l = vec3(0.0);
        for (uint i = 0u; i + j <= n; ++i) {
            vec3 p = spectral_points[k].xyz;
            uint l = n - i - j;
            row += a[i] * c[l] * p;
            row_xi += da[i] * c[l] * p;
            row_l += a[i] * dc[l] * p;
            ++k;
        }
        x += b[j] * row;
        dxi += b[j] * (row_xi - row_l);
        deta += db[j] * row - b[j] * row_l;
    }
    return x;
}

// Field slot `slot`'s value of triangle e at r, sum L_ij F_ij, and its derivatives along xi and
// eta in `gradient` when asked; the coefficients from `given` when `from_given` (the flat
// varyings, spectral_flat_coefficients) and from the buffer otherwise.
float simplex_triangle_sum(uint e, uint slot, bool from_given, vec4 given[SPECTRAL_FLAT_VEC4S], vec2 r,
                           bool want_gradient, out vec2 gradient) {
    const uint n = SPECTRAL_FIELD_ORDER;
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES];
    simplex_silvester(n, r.x, want_gradient, a, da);
    simplex_silvester(n, r.y, want_gradient, b, db);
    simplex_silvester(n, 1.0 - r.x - r.y, want_gradient, c, dc);
    uint base = e * SPECTRAL_ELEMENT_VEC4S + slot * SPECTRAL_VALUE_VEC4S;
    uint t = 0u;
    float v = 0.0;
    gradient = vec2(0.0);
    for (uint j = 0u; j <= n; ++j) {
        float row = 0.0, row_xi = 0.0, row_l = 0.0;
        for (uint i = 0u; i + j <= n; ++i) {
            vec4 q = from_given ? given[min(t >> 2u, SPECTRAL_FLAT_VEC4S - 1u)] : spectral_values[base + (t >> 2u)];
            float f = q[t & 3u];
            uint l = n - i - j;
            row += a[i] * c[l] * f;
            row_xi += da[i] * c[l] * f;
            row_l += a[i] * dc[l] * f;
            ++t;
        }
        v += b[j] * row;
        gradient += vec2(b[j] * (row_xi - row_l), db[j] * row - b[j] * row_l);
    }
    return v;
}

// Tetrahedra (SPECTRAL_DIM == 3): L_ijk = R_i(xi) R_j(eta) R_k(zeta) R_l(1 - xi - eta - zeta),
// l = n - i - j - k; node (i, j, k) in layers of constant k, each a triangle of order n - k in
// rows (simplex::tetra_index). Twin of simplex::tetra_terms.

// The geometry map of tetrahedron e at r and its Jacobian (columns d/dxi, d/deta, d/dzeta).
vec3 simplex_tetra_map(uint e, vec3 r, out mat3 jacobian) {
    const uint n = SPECTRAL_GEOMETRY_ORDER;
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES], w[SPECTRAL_MAX_NODES], dw[SPECTRAL_MAX_NODES];
    simplex_silvester(n, r.x, true, a, da);
    simplex_silvester(n, r.y, true, b, db);
    simplex_silvester(n, r.z, true, c, dc);
    simplex_silvester(n, 1.0 - r.x - r.y - r.z, true, w, dw);
    uint q = e * ((n + 1u) * (n + 2u) * (n + 3u) / 6u);
    vec3 x = vec3(0.0), dx = vec3(0.0), dy = vec3(0.0), dz = vec3(0.0);
    for (uint k = 0u; k <= n; ++k) {
        for (uint j = 0u; j + k <= n; ++j) {
            for (uint i = 0u; i + j + k <= n; ++i) {
                vec3 p = spectral_points[q].xyz;
                uint l = n - i - j - k;
                float abc = a[i] * b[j] * c[k];
                float dl = abc * dw[l];
                x += abc * w[l] * p;
                dx += (da[i] * b[j] * c[k] * w[l] - dl) * p;
                dy += (a[i] * db[j] * c[k] * w[l] - dl) * p;
                dz += (a[i] * b[j] * dc[k] * w[l] - dl) * p;
                ++q;
            }
        }
    }
    jacobian = mat3(dx, dy, dz);
    return x;
}

// Field slot `slot`'s value of tetrahedron e at r and, when asked, its derivatives along xi,
// eta, zeta in `gradient` (coefficients from the buffer).
float simplex_tetra_sum(uint e, uint slot, vec3 r, bool want_gradient, out vec3 gradient) {
    const uint n = SPECTRAL_FIELD_ORDER;
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES], w[SPECTRAL_MAX_NODES], dw[SPECTRAL_MAX_NODES];
    simplex_silvester(n, r.x, want_gradient, a, da);
    simplex_silvester(n, r.y, want_gradient, b, db);
    simplex_silvester(n, r.z, want_gradient, c, dc);
    simplex_silvester(n, 1.0 - r.x - r.y - r.z, want_gradient, w, dw);
    uint base = e * SPECTRAL_ELEMENT_VEC4S + slot * SPECTRAL_VALUE_VEC4S;
    uint t = 0u;
    float v = 0.0;
    gradient = vec3(0.0);
    for (uint k = 0u; k <= n; ++k) {
        for (uint j = 0u; j + k <= n; ++j) {
            for (uint i = 0u; i + j + k <= n; ++i) {
                float f = spectral_values[base + (t >> 2u)][t & 3u];
                uint l = n - i - j - k;
                float abc = a[i] * b[j] * c[k];
                v += abc * w[l] * f;
                if (want_gradient) {
                    float dl = abc * dw[l];
                    gradient += f * vec3(da[i] * b[j] * c[k] * w[l] - dl, a[i] * db[j] * c[k] * w[l] - dl,
                                         a[i] * b[j] * dc[k] * w[l] - dl);
                }
                ++t;
            }
        }
    }
    return v;
}

#endif
