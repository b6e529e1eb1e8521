// The geometry of one simplex, dimension-generic (dim 2: triangles, z = 0; dim 3: tetrahedra).
// Twin of src/mesh/geometry.rs (signed_volume, face_area_normal, centroid, face_centroid) and
// src/fluid/particles.rs (barycentric); the particle tests check the two agree.
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

// Outward area normal of the face opposite vertex k: −d ∂vol/∂x_k.
vec3 simplex_face_normal(uint dim, vec3 p[4], uint k) {
    if (dim == 2u) {
        vec3 a = p[(k + 1u) % 3u];
        vec3 b = p[(k + 2u) % 3u];
        return vec3(b.y - a.y, -(b.x - a.x), 0.0);
    }
    vec3 g1 = cross(p[2] - p[0], p[3] - p[0]);
    vec3 g2 = cross(p[3] - p[0], p[1] - p[0]);
    vec3 g3 = cross(p[1] - p[0], p[2] - p[0]);
    vec3 g = k == 0u ? -(g1 + g2 + g3) : (k == 1u ? g1 : (k == 2u ? g2 : g3));
    return -0.5 * g;
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

// Barycentric weight of vertex k at x: 1 − (x − p_k)·(A_k n_k) / (d vol).
float simplex_barycentric(uint dim, vec3 p[4], float vol, uint k, vec3 x) {
    return 1.0 - dot(x - p[k], simplex_face_normal(dim, p, k)) / (float(dim) * vol);
}

#endif
