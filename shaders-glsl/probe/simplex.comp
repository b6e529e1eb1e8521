#version 450
// Test probe: evaluates simplex.glsl (twin of src/mesh/geometry.rs and the barycentric
// coordinates of src/fluid/particles.rs) on given simplices and points.
#include "simplex.glsl"

layout(local_size_x = 64) in;
// Per probe: four corners (xyz, w unused) and a point (xyz, w = dimension).
layout(std430, set = 0, binding = 0) readonly buffer Corners { vec4 corners[]; };
layout(std430, set = 0, binding = 1) readonly buffer Points { vec4 points[]; };
// Per probe, 4 vec4: (volume, 0, 0, 0), centroid, face centroid of face 0, barycentric weights.
layout(std430, set = 0, binding = 2) writeonly buffer Out { vec4 result[]; };
layout(push_constant) uniform Push { uint n; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    uint dim = uint(points[i].w);
    vec3 p[4];
    for (uint k = 0u; k < 4u; ++k) p[k] = corners[4u * i + k].xyz;
    result[4u * i] = vec4(simplex_volume(dim, p), 0.0, 0.0, 0.0);
    result[4u * i + 1u] = vec4(simplex_centroid(dim, p), 0.0);
    result[4u * i + 2u] = vec4(simplex_face_centroid(dim, p, 0u), 0.0);
    result[4u * i + 3u] = simplex_barycentrics(dim, p, points[i].xyz);
}
