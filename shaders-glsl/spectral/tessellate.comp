#version 450
// Adaptive tessellation of curved surface elements on the device (seed 002's surfaces): each
// element becomes an L × L grid of its reference square (two triangles per cell), every vertex
// the exact geometry map at its reference coordinates, with L chosen per element and frame so
// that every point of the triangles lies within the screen-space error budget of the surface.
//
// A right triangle with legs h = 1/L has circumradius R = h / sqrt(2), and linear interpolation
// at its vertices errs by at most R² / 2 · sup_u |D²_u x| (Waldron 1998) ≤ h² / 4 · K, where
// K = max(|x_ξξ|, |x_ηη|) + |x_ξη| bounds the directional second derivatives of the geometry
// map (from its Bernstein control net, src/spectral/proxy.rs). A world error e moves the image
// of a point at view coordinates (X, Y, Z) by at most f e (1 + |(X, Y)| / Z) / Z pixels (f:
// pixels per world unit at view depth 1); over the element's sphere (centre c, radius r),
// Z ≥ z = depth(c) − r and |X| / Z ≤ (|clip_x(c)| + s_x r) / (s_x z) with s_x the length of the
// view-projection's first row (likewise Y), so P = f (1 + |(t_x, t_y)|) bounds the scale. So
// L = ceil(sqrt(P K / (4 z budget))) keeps every point within `budget` pixels, up to the level
// cap. Twin: proxy::tessellation_level.
//
// Triangles (SPECTRAL_SIMPLEX): the reference triangle in L rows of right triangles with legs
// 1/L (L² of them: row j has L - j upright and L - j - 1 inverted), so the same bound holds with
// K from the simplex Bernstein net (proxy.rs); 3 L² vertices.
//
// One invocation per element (lanes run across elements, no barriers): it reserves 6 L² (3 L²)
// vertices in the output (a compare-and-swap that never passes the capacity: an element that
// does not fit is skipped and counted), then walks its cells row by row, evaluating each grid
// point once per row pair (the previous column's two points carry over).
#include "spectral_element.glsl"
#include "spectral_push.glsl"

layout(local_size_x = 64) in;
#include "spectral_patches.glsl"
// The draw's VkDrawIndirectCommand (vertex count first), its capacity, elements skipped.
layout(std430, set = 0, binding = 4) buffer Draw { uint vertex_count; uint instances; uint first_vertex; uint first_instance; uint capacity; uint skipped; } draw;
struct DrawVertex { float x, y, z, xi, eta; uint element; };
layout(std430, set = 0, binding = 5) writeonly buffer Vertices { DrawVertex vertices[]; };

uint tessellation_level(SpectralPatch p) {
    float r = p.centre_radius.w;
    vec4 c = pc.view_proj * vec4(p.centre_radius.xyz, 1.0);
    float depth = c.w - r;
    if (depth + 2.0 * r <= 0.0) return 0u;  // wholly behind the eye
    float z = max(depth, 1e-3 * r);
    float sx = length(vec3(pc.view_proj[0][0], pc.view_proj[1][0], pc.view_proj[2][0]));
    float sy = length(vec3(pc.view_proj[0][1], pc.view_proj[1][1], pc.view_proj[2][1]));
    float tx = (abs(c.x) + sx * r) / (sx * z);
    float ty = (abs(c.y) + sy * r) / (sy * z);
    float pixels = pc.pixel_to_world.w * (1.0 + sqrt(tx * tx + ty * ty));
    float l = ceil(sqrt(pixels / z * p.curvature.x / (4.0 * pc.misc.z)));
    return uint(clamp(l, 1.0, pc.misc.w));
}

// The (lifted) surface point at r.
vec3 surface_point(uint e, vec2 r, float height) {
    vec3 dxi, deta;
    vec3 x = spectral_map(e, r, dxi, deta);
    if (height != 0.0) x.z = height * spectral_value(e, r);
    return x;
}

void main() {
    uint e = gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x + gl_GlobalInvocationID.x;
    if (e >= patches.length()) return;
    uint l = tessellation_level(patches[e]);
    uint n = (SPECTRAL_SIMPLEX ? 3u : 6u) * l * l;
    if (n == 0u) return;
    uint base = draw.vertex_count;
    while (true) {
        if (base + n > draw.capacity) {
            atomicAdd(draw.skipped, 1u);
            return;
        }
        uint seen = atomicCompSwap(draw.vertex_count, base, base + n);
        if (seen == base) break;
        base = seen;
    }
    float height = patches[e].curvature.y;
    uint k = base;
    if (SPECTRAL_SIMPLEX) {
        for (uint j = 0u; j < l; ++j) {
            vec2 r00 = vec2(0u, j) / float(l), r01 = vec2(0u, j + 1u) / float(l);
            vec3 x00 = surface_point(e, r00, height), x01 = surface_point(e, r01, height);
            for (uint i = 0u; i + j < l; ++i) {
                vec2 r10 = vec2(i + 1u, j) / float(l);
                vec3 x10 = surface_point(e, r10, height);
                vertices[k + 0u] = DrawVertex(x00.x, x00.y, x00.z, r00.x, r00.y, e);
                vertices[k + 1u] = DrawVertex(x10.x, x10.y, x10.z, r10.x, r10.y, e);
                vertices[k + 2u] = DrawVertex(x01.x, x01.y, x01.z, r01.x, r01.y, e);
                k += 3u;
                if (i + j + 1u < l) {
                    vec2 r11 = vec2(i + 1u, j + 1u) / float(l);
                    vec3 x11 = surface_point(e, r11, height);
                    vertices[k + 0u] = DrawVertex(x10.x, x10.y, x10.z, r10.x, r10.y, e);
                    vertices[k + 1u] = DrawVertex(x11.x, x11.y, x11.z, r11.x, r11.y, e);
                    vertices[k + 2u] = DrawVertex(x01.x, x01.y, x01.z, r01.x, r01.y, e);
                    k += 3u;
                    x01 = x11;
                    r01 = r11;
                }
                x00 = x10;
                r00 = r10;
            }
        }
        return;
    }
    for (uint j = 0u; j < l; ++j) {
        vec2 r00 = vec2(0u, j) / float(l), r01 = vec2(0u, j + 1u) / float(l);
        vec3 x00 = surface_point(e, r00, height), x01 = surface_point(e, r01, height);
        for (uint i = 0u; i < l; ++i) {
            vec2 r10 = vec2(i + 1u, j) / float(l), r11 = vec2(i + 1u, j + 1u) / float(l);
            vec3 x10 = surface_point(e, r10, height), x11 = surface_point(e, r11, height);
            vertices[k + 0u] = DrawVertex(x00.x, x00.y, x00.z, r00.x, r00.y, e);
            vertices[k + 1u] = DrawVertex(x10.x, x10.y, x10.z, r10.x, r10.y, e);
            vertices[k + 2u] = DrawVertex(x11.x, x11.y, x11.z, r11.x, r11.y, e);
            vertices[k + 3u] = DrawVertex(x00.x, x00.y, x00.z, r00.x, r00.y, e);
            vertices[k + 4u] = DrawVertex(x11.x, x11.y, x11.z, r11.x, r11.y, e);
            vertices[k + 5u] = DrawVertex(x01.x, x01.y, x01.z, r01.x, r01.y, e);
            k += 6u;
            x00 = x10;
            x01 = x11;
            r00 = r10;
            r01 = r11;
        }
    }
}
