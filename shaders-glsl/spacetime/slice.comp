#version 450
// Slices the active range of a spacetime mesh (sorted by lowest time) with the plane t
// (seed 003 §4.1); the device twin of src/spacetime/slice.rs (same below/above rule, same cut
// formula, same corner order). Each cut polygon is fanned into triangles, each triangle
// quadrisected `level` times where its area exceeds `max_area` (§4.2.2), and its edges are
// emitted as lines for the edge overdraw (§4.3). Output is appended with atomics to vertex
// buffers whose counts are the vertexCount of two indirect draws.
layout(local_size_x = 64) in;

struct SliceVertex { vec2 xy; uint element; float pad; };
layout(std430, set = 0, binding = 0) readonly buffer Vertices { vec4 vertices[]; };   // x, y, t, 0
layout(std430, set = 0, binding = 1) readonly buffer Tets { uvec4 tets[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Tris { SliceVertex tris[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Lines { SliceVertex lines[]; };
// Two VkDrawIndirectCommand (triangles, lines), then the overflow flag.
layout(std430, set = 0, binding = 4) buffer Draws { uint draws[9]; };
layout(push_constant) uniform Push {
    uint first; uint count; float t; float max_area;
    uint max_level; uint tri_capacity; uint line_capacity; uint pad;
} pc;

vec2 cut(vec3 below, vec3 above) {
    float s = (pc.t - below.z) / (above.z - below.z);
    return below.xy + s * (above.xy - below.xy);
}

void emit_triangle(vec2 a, vec2 b, vec2 c, uint element) {
    float area = 0.5 * abs((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
    uint level = 0u;
    while (area > pc.max_area && level < pc.max_level) { area *= 0.25; level++; }
    uint n = 1u << level;
    uint at = atomicAdd(draws[0], 3u * n * n);
    if (at + 3u * n * n > pc.tri_capacity) { draws[8] = 1u; return; }
    float inv = 1.0 / float(n);
    for (uint i = 0u; i < n; ++i) {
        for (uint j = 0u; j < n - i; ++j) {
            vec2 p00 = a + (float(i) * inv) * (b - a) + (float(j) * inv) * (c - a);
            vec2 p10 = p00 + inv * (b - a);
            vec2 p01 = p00 + inv * (c - a);
            tris[at++] = SliceVertex(p00, element, 0.0);
            tris[at++] = SliceVertex(p10, element, 0.0);
            tris[at++] = SliceVertex(p01, element, 0.0);
            if (j + 1u < n - i) {
                tris[at++] = SliceVertex(p10, element, 0.0);
                tris[at++] = SliceVertex(p10 + inv * (c - a), element, 0.0);
                tris[at++] = SliceVertex(p01, element, 0.0);
            }
        }
    }
}

void main() {
    uint k = gl_GlobalInvocationID.x;
    if (k >= pc.count) return;
    uint element = pc.first + k;
    uvec4 tet = tets[element];
    vec3 p[4] = vec3[4](vertices[tet.x].xyz, vertices[tet.y].xyz, vertices[tet.z].xyz, vertices[tet.w].xyz);
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
    for (uint i = 1u; i + 1u < corners; ++i) emit_triangle(c[0], c[i], c[i + 1u], element);
    uint at = atomicAdd(draws[4], 2u * corners);
    if (at + 2u * corners > pc.line_capacity) { draws[8] = 1u; return; }
    for (uint i = 0u; i < corners; ++i) {
        lines[at++] = SliceVertex(c[i], element, 0.0);
        lines[at++] = SliceVertex(c[(i + 1u) % corners], element, 0.0);
    }
}
