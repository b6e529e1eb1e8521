// A quadrilateral spectral element on the device (seed 002): its geometry map and Jacobian,
// the inverse map by Newton's method, and the field value, all as tensor products of the 1D
// bases of lagrange.glsl. Declares the renderer's element buffers (bindings 0, 1 and 3).
// Twin of src/spectral/mesh.rs (SpectralMesh::map, value, inverse_map).
#ifndef GALERKIN_SPECTRAL_ELEMENT_GLSL
#define GALERKIN_SPECTRAL_ELEMENT_GLSL
#include "lagrange.glsl"

// Geometry control points, (g + 1)^2 per element, node (i, j) at e (g+1)^2 + j (g+1) + i.
layout(std430, set = 0, binding = 0) readonly buffer SpectralGeometry { vec4 spectral_points[]; };
// Field coefficients of the shown field and step, (n + 1)^2 per element, same order.
layout(std430, set = 0, binding = 1) readonly buffer SpectralValues { float spectral_values[]; };
layout(std430, set = 0, binding = 3) readonly buffer SpectralBases {
    SpectralBasis spectral_field_basis;
    SpectralBasis spectral_geometry_basis;
};

// Newton steps of the per-fragment inverse map (NEWTON_ITERATIONS of mesh.rs).
#define SPECTRAL_NEWTON_ITERATIONS 12

// The geometry map x(xi, eta) of element e and its derivatives along xi and eta.
vec3 spectral_map(uint e, vec2 r, out vec3 dxi, out vec3 deta) {
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    spectral_basis_eval(spectral_geometry_basis, r.x, true, a, da);
    spectral_basis_eval(spectral_geometry_basis, r.y, true, b, db);
    uint m = spectral_geometry_basis.order + 1u;
    uint base = e * m * m;
    vec3 x = vec3(0.0);
    dxi = vec3(0.0);
    deta = vec3(0.0);
    for (uint j = 0u; j < m; ++j) {
        vec3 row = vec3(0.0), drow = vec3(0.0);
        for (uint i = 0u; i < m; ++i) {
            vec3 p = spectral_points[base + j * m + i].xyz;
            row += a[i] * p;
            drow += da[i] * p;
        }
        x += b[j] * row;
        dxi += b[j] * drow;
        deta += db[j] * row;
    }
    return x;
}

// The field value of element e at reference point r: sum_j l_j(eta) sum_i l_i(xi) F_ij.
float spectral_value(uint e, vec2 r) {
    float a[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], unused[SPECTRAL_MAX_NODES];
    spectral_basis_eval(spectral_field_basis, r.x, false, a, unused);
    spectral_basis_eval(spectral_field_basis, r.y, false, b, unused);
    uint m = spectral_field_basis.order + 1u;
    uint base = e * m * m;
    float v = 0.0;
    for (uint j = 0u; j < m; ++j) {
        float row = 0.0;
        for (uint i = 0u; i < m; ++i) row += a[i] * spectral_values[base + j * m + i];
        v += b[j] * row;
    }
    return v;
}

// Newton's method for the reference point of planar element e that maps to p, from r; returns
// false if it diverged. Stops when the step is below 1e-6 (a few f32 ulps of [0, 1]).
bool spectral_inverse_map(uint e, vec2 p, inout vec2 r) {
    for (int k = 0; k < SPECTRAL_NEWTON_ITERATIONS; ++k) {
        vec3 dxi, deta;
        vec2 f = spectral_map(e, r, dxi, deta).xy - p;
        float det = dxi.x * deta.y - deta.x * dxi.y;
        if (det == 0.0) return false;
        vec2 s = vec2(deta.y * f.x - deta.x * f.y, -dxi.y * f.x + dxi.x * f.y) / det;
        r -= s;
        if (any(greaterThan(abs(r), vec2(10.0)))) return false;
        if (max(abs(s.x), abs(s.y)) < 1e-6) return true;
    }
    return true;
}

#endif
