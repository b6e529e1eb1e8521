// The geometry of one simplex, dimension-generic (dim 2: triangles, z = 0; dim 3: tetrahedra).
// Twin of src/mesh/geometry.rs (signed_volume, centroid, face_centroid) and
// src/fluid/particles.rs (barycentric); tests/includes_agree.rs checks the two agree.
#ifndef GALERKIN_SIMPLEX_GLSL
#define GALERKIN_SIMPLEX_GLSL

// det[p1 − p0, …] / d!.
float simplex_volume(uint dim, vec3 p[4]) {
    vec3 a = p[1] - p[0];
    vec3 b = p[2] - p[0];
    if (dim == 2u) {
        return 0.5 * (a.x * b.y - a.y * b.x);
    }
    return dot(a, cross(b, p[3] - p[0])) / 6.0;
}

vec3 simplex_centroid(uint dim, vec3 p[4]) {
    vec3 c = p[0] + p[1] + p[2];
    if (dim == 3u) {
        c += p[3];
    }
    return c / float(dim + 1u);
}

// Centroid of the face opposite vertex k.
vec3 simplex_face_centroid(uint dim, vec3 p[4], uint k) {
    vec3 c = vec3(0.0);
    for (uint i = 0u; i <= dim; ++i) {
        if (i != k) {
            c += p[i];
        }
    }
    return c / float(dim);
}

// Barycentric weights of x (xyz, then w for a tetrahedron's fourth vertex): with edges
// e_i = p_i − p_0 and r = x − p_0, λ_i = r·g_i / (e_1·g_1) for i ≥ 1 (g_i the gradient of the
// scaled volume with respect to p_i: in 3D g_1 = e_2 × e_3, g_2 = e_3 × e_1, g_3 = e_1 × e_2),
// λ_0 = 1 − Σ λ_i. Twin of barycentric in src/fluid/particles.rs.
vec4 simplex_barycentrics(uint dim, vec3 p[4], vec3 x) {
    vec3 r = x - p[0];
    vec3 e1 = p[1] - p[0];
    vec3 e2 = p[2] - p[0];
    vec4 b = vec4(0.0);
    if (dim == 2u) {
        float det = e1.x * e2.y - e1.y * e2.x;
        b.y = (r.x * e2.y - r.y * e2.x) / det;
        b.z = (e1.x * r.y - e1.y * r.x) / det;
    } else {
        vec3 e3 = p[3] - p[0];
        vec3 g1 = cross(e2, e3);
        float det = dot(e1, g1);
        b.y = dot(r, g1) / det;
        b.z = dot(r, cross(e3, e1)) / det;
        b.w = dot(r, cross(e1, e2)) / det;
    }
    b.x = 1.0 - b.y - b.z - b.w;
    return b;
}

#endif
