// Rays through solid elements, shared by the isosurface and volume passes (spectral_iso_frag.glsl,
// volume.frag): the slab test of an element's box, the clip to its hull's half-spaces (with
// SPECTRAL_HULL_BINDING defined) and the retried pull-back of a point on the ray. Twins: iso_reference::slab and iso_reference::pull_back. Needs spectral_element.glsl
// and GL_EXT_control_flow_attributes (enabled by the including shader, after #version).
#ifndef GALERKIN_SPECTRAL_RAY_GLSL
#define GALERKIN_SPECTRAL_RAY_GLSL

// The ray's parameters (from eye along unit d, t >= 0) where it enters and leaves the box
// [lo, hi]: it crosses the box when x < y.
vec2 spectral_ray_box(vec3 eye, vec3 d, vec3 lo, vec3 hi) {
    vec3 inv = 1.0 / d;
    vec3 ta = (lo - eye) * inv, tb = (hi - eye) * inv;
    vec3 tmin = min(ta, tb), tmax = max(ta, tb);
    return vec2(max(0.0, max(tmin.x, max(tmin.y, tmin.z))), min(tmax.x, min(tmax.y, tmax.z)));
}

#ifdef SPECTRAL_HULL_BINDING
// Per element SPECTRAL_HULL_PLANES half-spaces n · x <= h whose intersection contains it: one
// per face of the straight element through its corners, h from its Bernstein control points
// (render/hull.rs, element_hull_planes; padded with 0 · x <= 1).
#define SPECTRAL_HULL_PLANES 6u
layout(std430, set = 0, binding = SPECTRAL_HULL_BINDING) readonly buffer Hulls { vec4 hull_planes[]; };

// The part of [t.x, t.y] of the ray (from eye along d) inside every half-space of element e:
// the ray meets the element only there; empty when x >= y.
vec2 spectral_ray_hull(uint e, vec3 eye, vec3 d, vec2 t) {
    for (uint k = 0u; k < SPECTRAL_HULL_PLANES; ++k) {
        vec4 p = hull_planes[e * SPECTRAL_HULL_PLANES + k];
        float rate = dot(p.xyz, d), room = p.w - dot(p.xyz, eye);
        if (rate > 0.0) {
            t.y = min(t.y, room / rate);
        } else if (rate < 0.0) {
            t.x = max(t.x, room / rate);
        } else if (room < 0.0) {
            t.y = -1.0;
        }
    }
    return t;
}
#endif

// Pulls x back into element e from r (warm start; once more from the element's centre if that
// fails): true when Newton converged; r unchanged when both failed.
bool spectral_pull_hex(uint e, vec3 x, inout vec3 r) {
    vec3 start = r;
    // One call site of the Newton loop (each inlined copy costs lavapipe a compile).
    [[dont_unroll]] for (int attempt = 0; attempt < 2; ++attempt) {
        if (spectral_inverse_map_hex(e, x, r)) return true;
        r = vec3(SPECTRAL_SIMPLEX ? 0.25 : 0.5);
    }
    r = start;
    return false;
}
#endif
