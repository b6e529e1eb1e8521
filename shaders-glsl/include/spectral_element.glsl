// A quadrilateral spectral element on the device (seed 002): its geometry map and Jacobian,
// the inverse map by Newton's method, and the field value, all as tensor products of the 1D
// bases of lagrange.glsl. Declares the renderer's element buffers (bindings 0 and 1) and the
// bases' specialization constants.
// Twin of src/spectral/mesh.rs (SpectralMesh::map, value, inverse_map).
#ifndef GALERKIN_SPECTRAL_ELEMENT_GLSL
#define GALERKIN_SPECTRAL_ELEMENT_GLSL
#include "lagrange.glsl"

// Geometry control points, (g + 1)^2 per element, node (i, j) at e (g+1)^2 + j (g+1) + i.
layout(std430, set = 0, binding = 0) readonly buffer SpectralGeometry { vec4 spectral_points[]; };
// Field coefficients of the shown field and step, (n + 1)^2 per element in the same order,
// each element's run padded with zeros to whole vec4s (SPECTRAL_VALUE_VEC4S per element): one
// vector load fetches four coefficients.
layout(std430, set = 0, binding = 1) readonly buffer SpectralValues { vec4 spectral_values[]; };
// The two bases as specialization constants (SpectralRenderer::specialization): field kind
// and order (ids 0, 1), field nodes (2–14) and weights (15–27), geometry kind and order (28,
// 29), geometry nodes (30–42) and weights (43–55).
layout(constant_id = 0) const uint SPECTRAL_FIELD_KIND = 0u;
layout(constant_id = 1) const uint SPECTRAL_FIELD_ORDER = 1u;
layout(constant_id = 2) const float SPECTRAL_FN0 = 0.0;
layout(constant_id = 3) const float SPECTRAL_FN1 = 1.0;
layout(constant_id = 4) const float SPECTRAL_FN2 = 0.0;
layout(constant_id = 5) const float SPECTRAL_FN3 = 0.0;
layout(constant_id = 6) const float SPECTRAL_FN4 = 0.0;
layout(constant_id = 7) const float SPECTRAL_FN5 = 0.0;
layout(constant_id = 8) const float SPECTRAL_FN6 = 0.0;
layout(constant_id = 9) const float SPECTRAL_FN7 = 0.0;
layout(constant_id = 10) const float SPECTRAL_FN8 = 0.0;
layout(constant_id = 11) const float SPECTRAL_FN9 = 0.0;
layout(constant_id = 12) const float SPECTRAL_FN10 = 0.0;
layout(constant_id = 13) const float SPECTRAL_FN11 = 0.0;
layout(constant_id = 14) const float SPECTRAL_FN12 = 0.0;
layout(constant_id = 15) const float SPECTRAL_FW0 = 0.0;
layout(constant_id = 16) const float SPECTRAL_FW1 = 0.0;
layout(constant_id = 17) const float SPECTRAL_FW2 = 0.0;
layout(constant_id = 18) const float SPECTRAL_FW3 = 0.0;
layout(constant_id = 19) const float SPECTRAL_FW4 = 0.0;
layout(constant_id = 20) const float SPECTRAL_FW5 = 0.0;
layout(constant_id = 21) const float SPECTRAL_FW6 = 0.0;
layout(constant_id = 22) const float SPECTRAL_FW7 = 0.0;
layout(constant_id = 23) const float SPECTRAL_FW8 = 0.0;
layout(constant_id = 24) const float SPECTRAL_FW9 = 0.0;
layout(constant_id = 25) const float SPECTRAL_FW10 = 0.0;
layout(constant_id = 26) const float SPECTRAL_FW11 = 0.0;
layout(constant_id = 27) const float SPECTRAL_FW12 = 0.0;
// Reference dimension: 2 (quadrilaterals) or 3 (hexahedra), id 56.
layout(constant_id = 56) const uint SPECTRAL_DIM = 2u;
// Lagrange triangles (spectral_simplex.glsl) instead of tensor-product elements, id 59.
layout(constant_id = 59) const bool SPECTRAL_SIMPLEX = false;
// Field and geometry share one basis (isoparametric elements), id 57.
layout(constant_id = 57) const bool SPECTRAL_SHARED_BASIS = false;
// Rational cells (SpectralMesh::weights, mesh.rs): spectral_points hold (w x, w y, w z, w), the
// coefficients are w F, and the map and the field divide by sum w B (one shared basis).
layout(constant_id = 58) const bool SPECTRAL_RATIONAL = false;
layout(constant_id = 28) const uint SPECTRAL_GEOMETRY_KIND = 0u;
layout(constant_id = 29) const uint SPECTRAL_GEOMETRY_ORDER = 1u;
layout(constant_id = 30) const float SPECTRAL_GN0 = 0.0;
layout(constant_id = 31) const float SPECTRAL_GN1 = 1.0;
layout(constant_id = 32) const float SPECTRAL_GN2 = 0.0;
layout(constant_id = 33) const float SPECTRAL_GN3 = 0.0;
layout(constant_id = 34) const float SPECTRAL_GN4 = 0.0;
layout(constant_id = 35) const float SPECTRAL_GN5 = 0.0;
layout(constant_id = 36) const float SPECTRAL_GN6 = 0.0;
layout(constant_id = 37) const float SPECTRAL_GN7 = 0.0;
layout(constant_id = 38) const float SPECTRAL_GN8 = 0.0;
layout(constant_id = 39) const float SPECTRAL_GN9 = 0.0;
layout(constant_id = 40) const float SPECTRAL_GN10 = 0.0;
layout(constant_id = 41) const float SPECTRAL_GN11 = 0.0;
layout(constant_id = 42) const float SPECTRAL_GN12 = 0.0;
layout(constant_id = 43) const float SPECTRAL_GW0 = 0.0;
layout(constant_id = 44) const float SPECTRAL_GW1 = 0.0;
layout(constant_id = 45) const float SPECTRAL_GW2 = 0.0;
layout(constant_id = 46) const float SPECTRAL_GW3 = 0.0;
layout(constant_id = 47) const float SPECTRAL_GW4 = 0.0;
layout(constant_id = 48) const float SPECTRAL_GW5 = 0.0;
layout(constant_id = 49) const float SPECTRAL_GW6 = 0.0;
layout(constant_id = 50) const float SPECTRAL_GW7 = 0.0;
layout(constant_id = 51) const float SPECTRAL_GW8 = 0.0;
layout(constant_id = 52) const float SPECTRAL_GW9 = 0.0;
layout(constant_id = 53) const float SPECTRAL_GW10 = 0.0;
layout(constant_id = 54) const float SPECTRAL_GW11 = 0.0;
layout(constant_id = 55) const float SPECTRAL_GW12 = 0.0;
#define SPECTRAL_FIELD_NODES float[SPECTRAL_MAX_NODES](SPECTRAL_FN0, SPECTRAL_FN1, SPECTRAL_FN2, SPECTRAL_FN3, SPECTRAL_FN4, SPECTRAL_FN5, SPECTRAL_FN6, SPECTRAL_FN7, SPECTRAL_FN8, SPECTRAL_FN9, SPECTRAL_FN10, SPECTRAL_FN11, SPECTRAL_FN12)
#define SPECTRAL_FIELD_WEIGHTS float[SPECTRAL_MAX_NODES](SPECTRAL_FW0, SPECTRAL_FW1, SPECTRAL_FW2, SPECTRAL_FW3, SPECTRAL_FW4, SPECTRAL_FW5, SPECTRAL_FW6, SPECTRAL_FW7, SPECTRAL_FW8, SPECTRAL_FW9, SPECTRAL_FW10, SPECTRAL_FW11, SPECTRAL_FW12)
#define SPECTRAL_GEOMETRY_NODES float[SPECTRAL_MAX_NODES](SPECTRAL_GN0, SPECTRAL_GN1, SPECTRAL_GN2, SPECTRAL_GN3, SPECTRAL_GN4, SPECTRAL_GN5, SPECTRAL_GN6, SPECTRAL_GN7, SPECTRAL_GN8, SPECTRAL_GN9, SPECTRAL_GN10, SPECTRAL_GN11, SPECTRAL_GN12)
#define SPECTRAL_GEOMETRY_WEIGHTS float[SPECTRAL_MAX_NODES](SPECTRAL_GW0, SPECTRAL_GW1, SPECTRAL_GW2, SPECTRAL_GW3, SPECTRAL_GW4, SPECTRAL_GW5, SPECTRAL_GW6, SPECTRAL_GW7, SPECTRAL_GW8, SPECTRAL_GW9, SPECTRAL_GW10, SPECTRAL_GW11, SPECTRAL_GW12)

// Whole vec4s of one element's coefficients.
#define SPECTRAL_VALUES_PER_ELEMENT (SPECTRAL_SIMPLEX ? (SPECTRAL_FIELD_ORDER + 1u) * (SPECTRAL_FIELD_ORDER + 2u) * (SPECTRAL_DIM == 3u ? SPECTRAL_FIELD_ORDER + 3u : 3u) / 6u : (SPECTRAL_FIELD_ORDER + 1u) * (SPECTRAL_FIELD_ORDER + 1u) * (SPECTRAL_DIM == 3u ? SPECTRAL_FIELD_ORDER + 1u : 1u))
#define SPECTRAL_VALUE_VEC4S ((SPECTRAL_VALUES_PER_ELEMENT + 3u) / 4u)
// Fields per element in spectral_values: 1 for the shipped shaders; a derived-field shader
// (src/expression, compiled at run time) defines more — each element's run is then the shown
// field's vec4s followed by those of every other field the expression names.
#ifndef SPECTRAL_FIELDS
#define SPECTRAL_FIELDS 1u
#endif
#define SPECTRAL_ELEMENT_VEC4S (SPECTRAL_FIELDS * SPECTRAL_VALUE_VEC4S)

// Elements whose coefficients fit four vec4s (quadrilaterals up to order 3) can hand them from
// the vertex stage to the fragment stage as flat varyings: on a CPU rasteriser a per-fragment
// read of the coefficient buffer (a gather per vec4) costs more than the evaluation itself.
#define SPECTRAL_FLAT_VEC4S 4u
#define SPECTRAL_FLAT_VALUES (SPECTRAL_DIM == 2u && SPECTRAL_VALUE_VEC4S <= SPECTRAL_FLAT_VEC4S)

// Lagrange triangles (SPECTRAL_SIMPLEX): the simplex map and sums.
#include "spectral_simplex.glsl"

// How far reference point r lies outside the element (negative inside): the largest of -xi,
// xi - 1, -eta, eta - 1 on the square, of -xi, -eta, xi + eta - 1 on the triangle.
// Twin of Shape::outside (mesh.rs).
float spectral_outside(vec2 r) {
    float low = max(-r.x, -r.y);
    return SPECTRAL_SIMPLEX ? max(low, r.x + r.y - 1.0) : max(low, max(r.x - 1.0, r.y - 1.0));
}

// spectral_outside in 3D: the cube's, or -xi, -eta, -zeta, xi + eta + zeta - 1 on the
// tetrahedron.
float spectral_outside_3d(vec3 r) {
    float low = max(-r.x, max(-r.y, -r.z));
    return SPECTRAL_SIMPLEX ? max(low, r.x + r.y + r.z - 1.0) : max(low, max(r.x - 1.0, max(r.y - 1.0, r.z - 1.0)));
}

// spectral_clamp in 3D.
vec3 spectral_clamp_3d(vec3 r) {
    vec3 c = clamp(r, 0.0, 1.0);
    float s = c.x + c.y + c.z;
    return SPECTRAL_SIMPLEX && s > 1.0 ? c / s : c;
}

// The point values are taken at once a fragment is accepted: each coordinate into [0, 1], and
// on the triangle xi + eta scaled back to 1. Twin of Shape::clamp (mesh.rs).
vec2 spectral_clamp(vec2 r) {
    vec2 c = clamp(r, 0.0, 1.0);
    return SPECTRAL_SIMPLEX && c.x + c.y > 1.0 ? c / (c.x + c.y) : c;
}

// The field's and the geometry's 1D bases at x.
void spectral_field_eval(float x, bool want_derivatives, out float v[SPECTRAL_MAX_NODES], out float d[SPECTRAL_MAX_NODES]) {
    spectral_basis_eval(SPECTRAL_FIELD_KIND, SPECTRAL_FIELD_ORDER, SPECTRAL_FIELD_NODES, SPECTRAL_FIELD_WEIGHTS, x, want_derivatives, v, d);
}
void spectral_geometry_eval(float x, bool want_derivatives, out float v[SPECTRAL_MAX_NODES], out float d[SPECTRAL_MAX_NODES]) {
    spectral_basis_eval(SPECTRAL_GEOMETRY_KIND, SPECTRAL_GEOMETRY_ORDER, SPECTRAL_GEOMETRY_NODES, SPECTRAL_GEOMETRY_WEIGHTS, x, want_derivatives, v, d);
}

// Newton steps of the per-fragment inverse map (NEWTON_ITERATIONS of mesh.rs).
#define SPECTRAL_NEWTON_ITERATIONS 12

// The geometry map of element e and its derivatives along xi and eta, from the geometry's 1D
// bases a (with derivatives da) at xi and b (db) at eta.
vec3 spectral_map_bases(uint e, float a[SPECTRAL_MAX_NODES], float da[SPECTRAL_MAX_NODES], float b[SPECTRAL_MAX_NODES],
                        float db[SPECTRAL_MAX_NODES], out vec3 dxi, out vec3 deta) {
    const uint m = SPECTRAL_GEOMETRY_ORDER + 1u;
    uint base = e * m * m;
    if (!SPECTRAL_RATIONAL) {
        // Polynomial cells: three components only (a vec4 sum costs lavapipe ~15 % here).
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
    // Rational cells: homogeneous sums, then the quotient.
    vec4 x = vec4(0.0), hxi = vec4(0.0), heta = vec4(0.0);
    for (uint j = 0u; j < m; ++j) {
        vec4 row = vec4(0.0), drow = vec4(0.0);
        for (uint i = 0u; i < m; ++i) {
            vec4 p = spectral_points[base + j * m + i];
            row += a[i] * p;
            drow += da[i] * p;
        }
        x += b[j] * row;
        hxi += b[j] * drow;
        heta += db[j] * row;
    }
    vec3 y = x.xyz / x.w;
    dxi = (hxi.xyz - y * hxi.w) / x.w;
    deta = (heta.xyz - y * heta.w) / x.w;
    return y;
}

// sum_ij a_i b_j w_ij over element e's rational weights (1.0 for polynomial cells).
float spectral_weight_sum(uint e, float a[SPECTRAL_MAX_NODES], float b[SPECTRAL_MAX_NODES]) {
    if (!SPECTRAL_RATIONAL) return 1.0;
    const uint m = SPECTRAL_GEOMETRY_ORDER + 1u;
    uint base = e * m * m;
    float w = 0.0;
    for (uint j = 0u; j < m; ++j) {
        float row = 0.0;
        for (uint i = 0u; i < m; ++i) row += a[i] * spectral_points[base + j * m + i].w;
        w += b[j] * row;
    }
    return w;
}

// The geometry map x(xi, eta) of element e and its derivatives along xi and eta.
vec3 spectral_map(uint e, vec2 r, out vec3 dxi, out vec3 deta) {
    if (SPECTRAL_SIMPLEX) return simplex_triangle_map(e, r, dxi, deta);
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    spectral_geometry_eval(r.x, true, a, da);
    spectral_geometry_eval(r.y, true, b, db);
    return spectral_map_bases(e, a, da, b, db, dxi, deta);
}


// Element e's coefficients as the flat varyings carry them (zeros for larger elements, which
// read the buffer instead).
void spectral_flat_coefficients(uint e, out vec4 f[SPECTRAL_FLAT_VEC4S]) {
    for (uint q = 0u; q < SPECTRAL_FLAT_VEC4S; ++q)
        f[q] = SPECTRAL_FLAT_VALUES && q < SPECTRAL_VALUE_VEC4S ? spectral_values[e * SPECTRAL_ELEMENT_VEC4S + q] : vec4(0.0);
}

// sum_ij a_i b_j F_ij over field slot k's coefficients of element e, taken from `given` when
// `from_given` (they travel as flat varyings) and from the buffer otherwise; the tensor weights are
// dotted with the coefficients four at a time.
float spectral_slot_tensor_sum(uint e, uint k, bool from_given, vec4 given[SPECTRAL_FLAT_VEC4S], float a[SPECTRAL_MAX_NODES],
                               float b[SPECTRAL_MAX_NODES]) {
    const uint m = SPECTRAL_FIELD_ORDER + 1u;
    uint base = e * SPECTRAL_ELEMENT_VEC4S + k * SPECTRAL_VALUE_VEC4S;
    float v = 0.0;
    for (uint q = 0u; q < SPECTRAL_VALUE_VEC4S; ++q) {
        vec4 w;
        for (uint c = 0u; c < 4u; ++c) {
            uint n = 4u * q + c;
            w[c] = n < m * m ? a[n % m] * b[n / m] : 0.0;
        }
        vec4 f = from_given ? given[min(q, SPECTRAL_FLAT_VEC4S - 1u)] : spectral_values[base + q];
        v += dot(w, f);
    }
    return SPECTRAL_RATIONAL ? v / spectral_weight_sum(e, a, b) : v;
}

// The shown field's sum (slot 0), from the flat varyings when SPECTRAL_FLAT_VALUES.
float spectral_tensor_sum(uint e, vec4 given[SPECTRAL_FLAT_VEC4S], float a[SPECTRAL_MAX_NODES], float b[SPECTRAL_MAX_NODES]) {
    return spectral_slot_tensor_sum(e, 0u, SPECTRAL_FLAT_VALUES, given, a, b);
}

// The field value of element e at reference point r, sum_ij l_i(xi) l_j(eta) F_ij, with the
// coefficients `given` as spectral_flat_coefficients makes them.
float spectral_value_given(uint e, vec2 r, vec4 given[SPECTRAL_FLAT_VEC4S]) {
    vec2 unused_gradient;
    if (SPECTRAL_SIMPLEX) return simplex_triangle_sum(e, 0u, SPECTRAL_FLAT_VALUES, given, r, false, unused_gradient);
    float a[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], unused[SPECTRAL_MAX_NODES];
    spectral_field_eval(r.x, false, a, unused);
    spectral_field_eval(r.y, false, b, unused);
    return spectral_tensor_sum(e, given, a, b);
}

// The field value of element e at reference point r.
float spectral_value(uint e, vec2 r) {
    vec4 given[SPECTRAL_FLAT_VEC4S];
    spectral_flat_coefficients(e, given);
    return spectral_value_given(e, r, given);
}

// The field value of element e at r (coefficients `given` as for spectral_value_given)
// together with the geometry map and its derivatives there — what a lit surface fragment
// needs. When field and geometry share one basis (isoparametric elements, the common case) the
// 1D bases are evaluated once for both.
float spectral_value_and_map(uint e, vec2 r, vec4 given[SPECTRAL_FLAT_VEC4S], out vec3 x, out vec3 dxi, out vec3 deta) {
    if (SPECTRAL_SIMPLEX) {
        x = simplex_triangle_map(e, r, dxi, deta);
        return spectral_value_given(e, r, given);
    }
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    spectral_geometry_eval(r.x, true, a, da);
    spectral_geometry_eval(r.y, true, b, db);
    x = spectral_map_bases(e, a, da, b, db, dxi, deta);
    return SPECTRAL_SHARED_BASIS ? spectral_tensor_sum(e, given, a, b) : spectral_value_given(e, r, given);
}

// Field slot k's value of element e at r and its derivatives along xi and eta: (f, f_xi,
// f_eta). Slot 0 is the shown field; a derived-field shader has SPECTRAL_FIELDS slots.
// Twin of SpectralMesh::value_gradient (mesh.rs).
vec3 spectral_slot_value_gradient(uint e, uint k, vec2 r) {
    if (SPECTRAL_SIMPLEX) {
        vec4 none[SPECTRAL_FLAT_VEC4S];
        vec2 g;
        float f = simplex_triangle_sum(e, k, false, none, r, true, g);
        return vec3(f, g);
    }
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    spectral_field_eval(r.x, true, a, da);
    spectral_field_eval(r.y, true, b, db);
    const uint m = SPECTRAL_FIELD_ORDER + 1u;
    uint base = e * SPECTRAL_ELEMENT_VEC4S + k * SPECTRAL_VALUE_VEC4S;
    vec3 v = vec3(0.0);
    for (uint q = 0u; q < SPECTRAL_VALUE_VEC4S; ++q) {
        vec4 f = spectral_values[base + q];
        for (uint c = 0u; c < 4u; ++c) {
            uint k = 4u * q + c;
            if (k < m * m) v += f[c] * vec3(a[k % m] * b[k / m], da[k % m] * b[k / m], a[k % m] * db[k / m]);
        }
    }
    if (!SPECTRAL_RATIONAL) return v;
    // (N / W)' = (N' - (N / W) W') / W, with W and its derivatives from the weights.
    vec3 w = vec3(0.0);
    for (uint k = 0u; k < m * m; ++k)
        w += spectral_points[e * m * m + k].w * vec3(a[k % m] * b[k / m], da[k % m] * b[k / m], a[k % m] * db[k / m]);
    float f = v.x / w.x;
    return vec3(f, (v.yz - f * w.yz) / w.x);
}

// The shown field's value of element e at r and its derivatives along xi and eta.
vec3 spectral_value_gradient(uint e, vec2 r) {
    return spectral_slot_value_gradient(e, 0u, r);
}

// The physical (surface) gradient of a field with reference derivatives d = (f_xi, f_eta) on a
// quadrilateral with tangents dxi, deta: [dxi deta] G^-1 d with the metric G = [t_i . t_j] —
// the inverse transpose of the Jacobian for planar elements, the tangential gradient on
// surfaces. Twin of expression::physical_gradient (src/expression/eval.rs).
vec3 spectral_physical_gradient(vec3 dxi, vec3 deta, vec2 d) {
    float g11 = dot(dxi, dxi), g12 = dot(dxi, deta), g22 = dot(deta, deta);
    float det = g11 * g22 - g12 * g12;
    vec2 c = vec2(g22 * d.x - g12 * d.y, -g12 * d.x + g11 * d.y) / det;
    return c.x * dxi + c.y * deta;
}

// Newton's method for the reference point of planar element e that maps to p, from r; returns
// false if it diverged or had not settled (last step over 1e-4: far more than f32 noise) when
// the iterations ran out. Stops when the step is below 1e-6 (a few f32 ulps of [0, 1]).
// Undamped, unlike the f64 reference's (mesh.rs): a fragment outside its element must leave
// quickly (|r| > 10), and most proxy fragments beyond an element are such.
bool spectral_inverse_map(uint e, vec2 p, inout vec2 r) {
    float last = 1.0;
    for (int k = 0; k < SPECTRAL_NEWTON_ITERATIONS; ++k) {
        vec3 dxi, deta;
        vec2 f = spectral_map(e, r, dxi, deta).xy - p;
        float det = dxi.x * deta.y - deta.x * dxi.y;
        if (det == 0.0) return false;
        vec2 s = vec2(deta.y * f.x - deta.x * f.y, -dxi.y * f.x + dxi.x * f.y) / det;
        r -= s;
        if (any(greaterThan(abs(r), vec2(10.0)))) return false;
        last = max(abs(s.x), abs(s.y));
        if (last < 1e-6) return true;
    }
    return last < 1e-4;
}

#ifdef SPECTRAL_EXPRESSION
// A derived field (src/expression): `spectral_expression(values, gradients, variables)`, written by
// the expression's translation to GLSL before this file is included, evaluated from every
// slot's value and physical gradient at r, the mapped point and the step's time. The time
// is the x of the vec4 after the last element's coefficients (DerivedField::padded_values;
// the buffer may be longer), SPECTRAL_ELEMENTS defined by the run-time source.
// Twin of DerivedField::value_at (src/expression/spectral.rs).
float spectral_time() {
    return spectral_values[SPECTRAL_ELEMENTS * SPECTRAL_ELEMENT_VEC4S].x;
}

// The expression of the slots' values and gradients at the mapped point x and the step's time
// (the variables of expression::SPECTRAL_VARIABLES: x, y, z, t).
float spectral_expression_at(float values[SPECTRAL_FIELDS], vec3 gradients[SPECTRAL_FIELDS], vec3 x) {
    vec3 variables[4] = vec3[4](vec3(x.x, 0.0, 0.0), vec3(x.y, 0.0, 0.0), vec3(x.z, 0.0, 0.0), vec3(spectral_time(), 0.0, 0.0));
    return spectral_expression(values, gradients, variables);
}
// Field slot k's value of element e at r (no derivatives), from the buffer (a derived-field
// shader's flat varyings hold only the shipped vertex stage's single-field view).
float spectral_slot_value(uint e, uint k, vec2 r) {
    vec4 none[SPECTRAL_FLAT_VEC4S];
    vec2 unused_gradient;
    if (SPECTRAL_SIMPLEX) return simplex_triangle_sum(e, k, false, none, r, false, unused_gradient);
    float a[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], unused[SPECTRAL_MAX_NODES];
    spectral_field_eval(r.x, false, a, unused);
    spectral_field_eval(r.y, false, b, unused);
    return spectral_slot_tensor_sum(e, k, false, none, a, b);
}

// Slots whose gradient the expression reads take the derivative sums
// (SPECTRAL_SLOT_GRADIENTS, written by the run-time source); the others their value only.
float spectral_derived_value(uint e, vec2 r) {
    vec3 dxi, deta;
    vec3 x = spectral_map(e, r, dxi, deta);
    float values[SPECTRAL_FIELDS];
    vec3 gradients[SPECTRAL_FIELDS];
    for (uint k = 0u; k < SPECTRAL_FIELDS; ++k) {
        if (SPECTRAL_SLOT_GRADIENTS[k]) {
            vec3 f = spectral_slot_value_gradient(e, k, r);
            values[k] = f.x;
            gradients[k] = spectral_physical_gradient(dxi, deta, f.yz);
        } else {
            values[k] = spectral_slot_value(e, k, r);
            gradients[k] = vec3(0.0);
        }
    }
    return spectral_expression_at(values, gradients, x);
}
#endif

// Hexahedra (SPECTRAL_DIM == 3): node (i, j, k) at e (g+1)^3 + k (g+1)^2 + j (g+1) + i.

// The geometry map x(xi, eta, zeta) of hexahedron e and its Jacobian (columns d/dxi, d/deta,
// d/dzeta).
vec3 spectral_map_hex(uint e, vec3 r, out mat3 jacobian) {
    if (SPECTRAL_SIMPLEX) return simplex_tetra_map(e, r, jacobian);
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES];
    spectral_geometry_eval(r.x, true, a, da);
    spectral_geometry_eval(r.y, true, b, db);
    spectral_geometry_eval(r.z, true, c, dc);
    const uint m = SPECTRAL_GEOMETRY_ORDER + 1u;
    uint base = e * m * m * m;
    if (!SPECTRAL_RATIONAL) {
        // Polynomial cells: three components only, as spectral_map_bases.
        vec3 x = vec3(0.0), dx = vec3(0.0), dy = vec3(0.0), dz = vec3(0.0);
        for (uint k = 0u; k < m; ++k) {
            vec3 layer = vec3(0.0), dlayer_x = vec3(0.0), dlayer_y = vec3(0.0);
            for (uint j = 0u; j < m; ++j) {
                vec3 row = vec3(0.0), drow = vec3(0.0);
                for (uint i = 0u; i < m; ++i) {
                    vec3 p = spectral_points[base + (k * m + j) * m + i].xyz;
                    row += a[i] * p;
                    drow += da[i] * p;
                }
                layer += b[j] * row;
                dlayer_x += b[j] * drow;
                dlayer_y += db[j] * row;
            }
            x += c[k] * layer;
            dx += c[k] * dlayer_x;
            dy += c[k] * dlayer_y;
            dz += dc[k] * layer;
        }
        jacobian = mat3(dx, dy, dz);
        return x;
    }
    // Rational cells: homogeneous sums, then the quotient.
    vec4 x = vec4(0.0), dx = vec4(0.0), dy = vec4(0.0), dz = vec4(0.0);
    for (uint k = 0u; k < m; ++k) {
        vec4 layer = vec4(0.0), dlayer_x = vec4(0.0), dlayer_y = vec4(0.0);
        for (uint j = 0u; j < m; ++j) {
            vec4 row = vec4(0.0), drow = vec4(0.0);
            for (uint i = 0u; i < m; ++i) {
                vec4 p = spectral_points[base + (k * m + j) * m + i];
                row += a[i] * p;
                drow += da[i] * p;
            }
            layer += b[j] * row;
            dlayer_x += b[j] * drow;
            dlayer_y += db[j] * row;
        }
        x += c[k] * layer;
        dx += c[k] * dlayer_x;
        dy += c[k] * dlayer_y;
        dz += dc[k] * layer;
    }
    vec3 y = x.xyz / x.w;
    jacobian = mat3((dx.xyz - y * dx.w) / x.w, (dy.xyz - y * dy.w) / x.w, (dz.xyz - y * dz.w) / x.w);
    return y;
}

// Field slot k's value of hexahedron e at r: sum_ijk l_i(xi) l_j(eta) l_k(zeta) F_ijk.
float spectral_value_hex_slot(uint e, uint slot, vec3 r) {
    vec3 unused_gradient;
    if (SPECTRAL_SIMPLEX) return simplex_tetra_sum(e, slot, r, false, unused_gradient);
    float a[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], c[SPECTRAL_MAX_NODES], unused[SPECTRAL_MAX_NODES];
    spectral_field_eval(r.x, false, a, unused);
    spectral_field_eval(r.y, false, b, unused);
    spectral_field_eval(r.z, false, c, unused);
    const uint m = SPECTRAL_FIELD_ORDER + 1u;
    uint base = e * SPECTRAL_ELEMENT_VEC4S + slot * SPECTRAL_VALUE_VEC4S;
    float v = 0.0;
    for (uint q = 0u; q < SPECTRAL_VALUE_VEC4S; ++q) {
        vec4 w;
        for (uint t = 0u; t < 4u; ++t) {
            uint k = 4u * q + t;
            w[t] = k < m * m * m ? a[k % m] * b[(k / m) % m] * c[k / (m * m)] : 0.0;
        }
        v += dot(w, spectral_values[base + q]);
    }
    if (!SPECTRAL_RATIONAL) return v;
    float weight = 0.0;
    for (uint k = 0u; k < m * m * m; ++k)
        weight += a[k % m] * b[(k / m) % m] * c[k / (m * m)] * spectral_points[e * m * m * m + k].w;
    return v / weight;
}

// The field value of hexahedron e at r: sum_ijk l_i(xi) l_j(eta) l_k(zeta) F_ijk.
float spectral_value_hex(uint e, vec3 r) {
    return spectral_value_hex_slot(e, 0u, r);
}

// Field slot k's value of hexahedron e at r and its derivatives along xi, eta, zeta:
// (f, f_xi, f_eta, f_zeta). Twin of SpectralMesh::value_gradient_at (gradient.rs).
vec4 spectral_slot_value_gradient_hex(uint e, uint k, vec3 r) {
    if (SPECTRAL_SIMPLEX) {
        vec3 g;
        float f = simplex_tetra_sum(e, k, r, true, g);
        return vec4(f, g);
    }
    float a[SPECTRAL_MAX_NODES], da[SPECTRAL_MAX_NODES], b[SPECTRAL_MAX_NODES], db[SPECTRAL_MAX_NODES];
    float c[SPECTRAL_MAX_NODES], dc[SPECTRAL_MAX_NODES];
    spectral_field_eval(r.x, true, a, da);
    spectral_field_eval(r.y, true, b, db);
    spectral_field_eval(r.z, true, c, dc);
    const uint m = SPECTRAL_FIELD_ORDER + 1u;
    uint base = e * SPECTRAL_ELEMENT_VEC4S + k * SPECTRAL_VALUE_VEC4S;
    vec4 v = vec4(0.0), w = vec4(0.0);
    for (uint q = 0u; q < SPECTRAL_VALUE_VEC4S; ++q) {
        vec4 f = spectral_values[base + q];
        for (uint t = 0u; t < 4u; ++t) {
            uint n = 4u * q + t;
            if (n >= m * m * m) break;
            uint i = n % m, j = (n / m) % m, l = n / (m * m);
            vec4 basis = vec4(a[i] * b[j] * c[l], da[i] * b[j] * c[l], a[i] * db[j] * c[l], a[i] * b[j] * dc[l]);
            v += f[t] * basis;
            if (SPECTRAL_RATIONAL) w += spectral_points[e * m * m * m + n].w * basis;
        }
    }
    if (!SPECTRAL_RATIONAL) return v;
    float value = v.x / w.x;
    return vec4(value, (v.yzw - value * w.yzw) / w.x);
}

// The physical gradient J^-T d of a field with reference derivatives d on a hexahedron with
// Jacobian j. Twin of expression::spectral::gradient.
vec3 spectral_physical_gradient_hex(mat3 j, vec3 d) {
    return transpose(inverse(j)) * d;
}

#ifdef SPECTRAL_EXPRESSION
// The derived field of hexahedron e at r (as spectral_derived_value, with the 3D gradient).
// Twin of DerivedField::value_at_hex (src/expression/spectral.rs).
float spectral_derived_value_hex(uint e, vec3 r) {
    mat3 j;
    vec3 x = spectral_map_hex(e, r, j);
    float values[SPECTRAL_FIELDS];
    vec3 gradients[SPECTRAL_FIELDS];
    for (uint k = 0u; k < SPECTRAL_FIELDS; ++k) {
        if (SPECTRAL_SLOT_GRADIENTS[k]) {
            vec4 f = spectral_slot_value_gradient_hex(e, k, r);
            values[k] = f.x;
            gradients[k] = spectral_physical_gradient_hex(j, f.yzw);
        } else {
            values[k] = spectral_value_hex_slot(e, k, r);
            gradients[k] = vec3(0.0);
        }
    }
    return spectral_expression_at(values, gradients, x);
}
#endif

// Newton's method for the reference point of hexahedron e that maps to p, from r; false if it
// diverged, met a singular Jacobian or had not settled (as spectral_inverse_map).
bool spectral_inverse_map_hex(uint e, vec3 p, inout vec3 r) {
    float last = 1.0;
    for (int k = 0; k < SPECTRAL_NEWTON_ITERATIONS; ++k) {
        mat3 j;
        vec3 f = spectral_map_hex(e, r, j) - p;
        if (determinant(j) == 0.0) return false;
        vec3 s = inverse(j) * f;
        r -= s;
        if (any(greaterThan(abs(r), vec3(10.0)))) return false;
        last = max(abs(s.x), max(abs(s.y), abs(s.z)));
        if (last < 1e-6) return true;
    }
    return last < 1e-4;
}

#endif
