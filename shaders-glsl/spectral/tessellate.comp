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
// by at most e · P / z pixels (P: pixels per world unit at view depth 1, times the off-axis
// factor), z ≥ the element's nearest view depth. So L = ceil(sqrt(P K / (4 z budget))) keeps
// every point within `budget` pixels, up to the level cap. Twin: proxy::tessellation_level.
//
// One workgroup per element: its first invocation reserves 6 L² vertices in the output (a
// compare-and-swap that never passes the capacity: an element that does not fit is skipped
// and counted), then the workgroup writes them.
#include "spectral_element.glsl"
#include "spectral_push.glsl"

layout(local_size_x = 64) in;
#include "spectral_patches.glsl"
// The draw's VkDrawIndirectCommand (vertex count first), its capacity, elements skipped.
layout(std430, set = 0, binding = 4) buffer Draw { uint vertex_count; uint instances; uint first_vertex; uint first_instance; uint capacity; uint skipped; } draw;
struct DrawVertex { float x, y, z, xi, eta; uint element; };
layout(std430, set = 0, binding = 5) writeonly buffer Vertices { DrawVertex vertices[]; };

shared uint base;
shared uint level;
// The grid's (L + 1)² points when they fit (L ≤ 15): each evaluated once, then copied into the
// six vertices of the cells around it. Larger levels evaluate per vertex.
#define GRID_POINTS 256u
shared vec3 grid[GRID_POINTS];

uint tessellation_level(SpectralPatch p) {
    float depth = (pc.view_proj * vec4(p.centre_radius.xyz, 1.0)).w - p.centre_radius.w;
    if (depth + 2.0 * p.centre_radius.w <= 0.0) return 0u;  // wholly behind the eye
    float z = max(depth, 1e-3 * p.centre_radius.w);
    float l = ceil(sqrt(pc.pixel_to_world.w / z * p.curvature.x / (4.0 * pc.misc.z)));
    return uint(clamp(l, 1.0, pc.misc.w));
}

void main() {
    uint e = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint elements = patches.length();
    if (gl_LocalInvocationID.x == 0u) {
        uint l = e < elements ? tessellation_level(patches[e]) : 0u;
        uint n = 6u * l * l;
        uint old = draw.vertex_count;
        while (n > 0u) {
            if (old + n > draw.capacity) {
                atomicAdd(draw.skipped, 1u);
                n = 0u;
                l = 0u;
                break;
            }
            uint seen = atomicCompSwap(draw.vertex_count, old, old + n);
            if (seen == old) break;
            old = seen;
        }
        base = old;
        level = l;
    }
    barrier();
    uint l = level;
    uint n = 6u * l * l;
    float height = e < elements ? patches[e].curvature.y : 0.0;
    uint points = (l + 1u) * (l + 1u);
    bool shared_grid = points <= GRID_POINTS;
    if (shared_grid) {
        for (uint k = gl_LocalInvocationID.x; k < points; k += 64u) {
            vec3 dxi, deta;
            vec2 r = vec2(k % (l + 1u), k / (l + 1u)) / float(l);
            grid[k] = spectral_map(e, r, dxi, deta);
            if (height != 0.0) grid[k].z = height * spectral_value(e, r);
        }
    }
    barrier();
    const uvec2 corner[6] = uvec2[6](uvec2(0, 0), uvec2(1, 0), uvec2(1, 1), uvec2(0, 0), uvec2(1, 1), uvec2(0, 1));
    for (uint k = gl_LocalInvocationID.x; k < n; k += 64u) {
        uint cell = k / 6u;
        uvec2 ij = uvec2(cell % l, cell / l) + corner[k % 6u];
        vec2 r = vec2(ij) / float(l);
        vec3 x;
        if (shared_grid) {
            x = grid[ij.y * (l + 1u) + ij.x];
        } else {
            vec3 dxi, deta;
            x = spectral_map(e, r, dxi, deta);
            if (height != 0.0) x.z = height * spectral_value(e, r);
        }
        vertices[base + k] = DrawVertex(x.x, x.y, x.z, r.x, r.y, e);
    }
}
