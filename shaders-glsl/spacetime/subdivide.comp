#version 450
// The second slicing pass (seed 003 §4.2.2): every cut triangle of slice.comp is quadrisected
// `level` times, the smallest level that brings its area to at most `max_area` (capped at
// `max_level`), and its 4^level triangles are appended to the vertex buffer of the triangle
// draw, |v| evaluated at every new vertex. The device twin of `subdivision_level` and `subdivide` in src/spacetime/slice.rs.
layout(local_size_x = 64) in;
#include "spacetime_slice.glsl"

layout(std430, set = 0, binding = 1) readonly buffer Cuts { vec4 cuts[]; };   // 3 vec4 each
layout(std430, set = 0, binding = 2) writeonly buffer Tris { SliceVertex tris[]; };

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= min(draws[9], pc.cut_capacity)) return;
    vec4 ab = cuts[3u * k], cw = cuts[3u * k + 1u], sp = cuts[3u * k + 2u];
    vec2 a = ab.xy, b = ab.zw, c = cw.xy;
    uint element = floatBitsToUint(cw.z);
    float area = 0.5 * abs((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
    uint level = 0u;
    while (area > pc.max_area && level < pc.max_level) { area *= 0.25; level++; }
    uint n = 1u << level;
    uint at = atomicAdd(draws[0], 3u * n * n);
    if (at + 3u * n * n > pc.tri_capacity) { draws[8] = 1u; return; }
    if (level == 0u) {
        // Unsubdivided: the corners' |v| from the cut pass.
        tris[at] = SliceVertex(a, element, cw.w);
        tris[at + 1u] = SliceVertex(b, element, sp.x);
        tris[at + 2u] = SliceVertex(c, element, sp.y);
        return;
    }
    // The element's restriction to the plane, read once for all the new vertices.
    SpacetimeSliceCubic restricted = cubics[element];
    float inv = 1.0 / float(n);
    for (uint i = 0u; i < n; ++i) {
        for (uint j = 0u; j < n - i; ++j) {
            vec2 p00 = a + (float(i) * inv) * (b - a) + (float(j) * inv) * (c - a);
            vec2 p10 = p00 + inv * (b - a);
            vec2 p01 = p00 + inv * (c - a);
            float s00 = spacetime_evaluate_slice(restricted, p00).speed;
            float s10 = spacetime_evaluate_slice(restricted, p10).speed;
            float s01 = spacetime_evaluate_slice(restricted, p01).speed;
            tris[at++] = SliceVertex(p00, element, s00);
            tris[at++] = SliceVertex(p10, element, s10);
            tris[at++] = SliceVertex(p01, element, s01);
            if (j + 1u < n - i) {
                vec2 p11 = p10 + inv * (c - a);
                tris[at++] = SliceVertex(p10, element, s10);
                tris[at++] = SliceVertex(p11, element, spacetime_evaluate_slice(restricted, p11).speed);
                tris[at++] = SliceVertex(p01, element, s01);
            }
        }
    }
}
