#version 450
// Slices the active range of a spacetime mesh (sorted by lowest time; element indices are
// positions in the resident window of records) with the plane t (seed 003 §4.1); the device twin of src/spacetime/slice.rs (same below/above rule, same cut
// formula, same corner order). Each cut polygon is fanned into triangles for subdivide.comp
// (the second pass) and its edges are emitted as lines for the edge overdraw (§4.3). Output is
// appended with atomics; the line count is the vertexCount of an indirect draw.
layout(local_size_x = 64) in;
#include "spacetime_slice.glsl"

// The resident window of the records (element k of the window = record first + k).
layout(std430, set = 0, binding = 0) readonly buffer Records { vec4 records[]; };   // 15 vec4 each
// Cut triangles for subdivide.comp: (a, b), (c, element bits, 0).
layout(std430, set = 0, binding = 1) writeonly buffer Cuts { vec4 cuts[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Lines { SliceVertex lines[]; };

vec2 cut(vec3 below, vec3 above) {
    float s = (pc.t - below.z) / (above.z - below.z);
    return below.xy + s * (above.xy - below.xy);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.count) return;
    uint element = pc.first + k;   // in the window
    // Corners (x0 y0 t0 x1)(y1 t1 x2 y2)(t2 x3 y3 t3): the first three vec4 of the record
    // (SpacetimeRecord in include/spacetime_cubic.glsl; read as vec4 to skip the coefficients).
    vec4 a = records[15u * element], b = records[15u * element + 1u], d = records[15u * element + 2u];
    vec3 p[4] = vec3[4](a.xyz, vec3(a.w, b.xy), vec3(b.zw, d.x), d.yzw);
    uint below[4], above[4];
    uint nb = 0u, na = 0u;
    for (uint i = 0u; i < 4u; ++i) {
        if (p[i].z < pc.t) below[nb++] = i; else above[na++] = i;
    }
    if (nb == 0u || na == 0u) return;
    vec2 c[4];
    uint corners;
    if (nb == 1u) {
        for (uint i = 0u; i < 3u; ++i) c[i] = cut(p[below[0]], p[above[i]]);
        corners = 3u;
    } else if (na == 1u) {
        for (uint i = 0u; i < 3u; ++i) c[i] = cut(p[below[i]], p[above[0]]);
        corners = 3u;
    } else {
        c[0] = cut(p[below[0]], p[above[0]]);
        c[1] = cut(p[below[0]], p[above[1]]);
        c[2] = cut(p[below[1]], p[above[1]]);
        c[3] = cut(p[below[1]], p[above[0]]);
        corners = 4u;
    }
    uint ncut = corners - 2u;
    uint cut_at = atomicAdd(draws[9], ncut);
    if (cut_at + ncut > pc.cut_capacity) { draws[8] = 1u; return; }
    for (uint i = 1u; i + 1u < corners; ++i) {
        cuts[2u * cut_at] = vec4(c[0], c[i]);
        cuts[2u * cut_at + 1u] = vec4(c[i + 1u], uintBitsToFloat(element), 0.0);
        cut_at++;
    }
    uint at = atomicAdd(draws[4], 2u * corners);
    if (at + 2u * corners > pc.line_capacity) { draws[8] = 1u; return; }
    for (uint i = 0u; i < corners; ++i) {
        lines[at++] = SliceVertex(c[i], element, 0.0);
        lines[at++] = SliceVertex(c[(i + 1u) % corners], element, 0.0);
    }
}
