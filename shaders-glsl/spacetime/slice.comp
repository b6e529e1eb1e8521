#version 450
// Slices the active range of a spacetime mesh (sorted by lowest time; element indices are
// positions in the resident window of records) with the plane t (seed 003 §4.1); the device
// twin of src/spacetime/slice.rs (same below/above rule, same cut formula, same corner order).
// Each cut element's cubic is restricted to the plane (for the subdivision pass and the
// fragment stage) and |v| evaluated at each polygon corner; the polygon is fanned into triangles for
// subdivide.comp (the second pass) and its edges are emitted as lines for the edge overdraw
// (§4.3). Output is appended with atomics; the line count is the vertexCount of an indirect
// draw.
layout(local_size_x = 64) in;
#include "spacetime_slice.glsl"

// Cut triangles for subdivide.comp: (a, b), (c, element bits, |v|(a)), (|v|(b), |v|(c), 0, 0).
layout(std430, set = 0, binding = 1) writeonly buffer Cuts { vec4 cuts[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Lines { SliceVertex lines[]; };

vec2 cut(vec3 below, vec3 above) {
    float s = (pc.t - below.z) / (above.z - below.z);
    return below.xy + s * (above.xy - below.xy);
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.count) return;
    uint element = (pc.first + k) % pc.capacity;   // the slot in the window's ring
    vec4 a = records[element].corners[0], b = records[element].corners[1], d = records[element].corners[2];
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
    SpacetimeRecord r = records[element];
    SpacetimeSliceCubic restricted =
        spacetime_restrict(spacetime_element(r, materials[floatBitsToUint(r.centre_material.w)]), pc.t);
    cubics[element] = restricted;
    float speed[4];
    for (uint i = 0u; i < corners; ++i) speed[i] = spacetime_evaluate_slice(restricted, c[i]).speed;
    uint ncut = corners - 2u;
    uint cut_at = atomicAdd(draws[9], ncut);
    if (cut_at + ncut > pc.cut_capacity) { draws[8] = 1u; return; }
    for (uint i = 1u; i + 1u < corners; ++i) {
        cuts[3u * cut_at] = vec4(c[0], c[i]);
        cuts[3u * cut_at + 1u] = vec4(c[i + 1u], uintBitsToFloat(element), speed[0]);
        cuts[3u * cut_at + 2u] = vec4(speed[i], speed[i + 1u], 0.0, 0.0);
        cut_at++;
    }
    uint at = atomicAdd(draws[4], 2u * corners);
    if (at + 2u * corners > pc.line_capacity) { draws[8] = 1u; return; }
    for (uint i = 0u; i < corners; ++i) {
        uint j = (i + 1u) % corners;
        lines[at++] = SliceVertex(c[i], element, speed[i]);
        lines[at++] = SliceVertex(c[j], element, speed[j]);
    }
}
