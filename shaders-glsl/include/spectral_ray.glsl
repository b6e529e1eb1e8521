// Rays through solid elements, shared by the isosurface and volume passes (spectral_iso_frag.glsl,
// volume.frag): the slab test of an element's box, the clip to its hull's half-spaces (with
// SPECTRAL_HULL_BINDING defined), the retried pull-back of a point on the ray, the bisection of
// a root along it and the shading of a level set's surface. Twins: iso_reference::slab and iso_reference::pull_back. Needs spectral_element.glsl
// and GL_EXT_control_flow_attributes (enabled by the including shader, after #version).
#ifndef GALERKIN_SPECTRAL_RAY_GLSL
#define GALERKIN_SPECTRAL_RAY_GLSL
#include "phong.glsl"

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
// Bisection of [t_lo, t_hi] for f − c = 0 along the ray from eye along d through element e (f
// continued past the element; g_lo = f − c at t_lo), at most SPECTRAL_RAY_BISECTIONS steps and
// none once the bracket is two f32 ulps of t wide, each point pulled back from r: the root's ray
// parameter, its reference point in r. Shared by the isosurface pass's roots and the volume
// pass's sheets.
#define SPECTRAL_RAY_BISECTIONS 24
// f32's unit roundoff (2^-23).
#define SPECTRAL_RAY_ULP 1.1920929e-7
float spectral_ray_bisect(uint e, vec3 eye, vec3 d, float t_lo, float t_hi, float c, float g_lo, inout vec3 r) {
    for (int i = 0; i < SPECTRAL_RAY_BISECTIONS; ++i) {
        float t = 0.5 * (t_lo + t_hi);
        // The bracket is two ulps of t wide: halving it again changes t by rounding only.
        if (t_hi - t_lo <= 2.0 * SPECTRAL_RAY_ULP * abs(t)) break;
        spectral_pull_hex(e, eye + t * d, r);
        float g = spectral_value_hex(e, r) - c;
        if ((g < 0.0) == (g_lo < 0.0)) t_lo = t; else t_hi = t;
    }
    float t = 0.5 * (t_lo + t_hi);
    spectral_pull_hex(e, eye + t * d, r);
    return t;
}

// The unit normal J⁻ᵀ∇_r f/|·| of a level set (Jacobian j, reference gradient g_r), −d where the
// gradient vanishes.
vec3 spectral_level_normal(mat3 j, vec3 g_r, vec3 d) {
    vec3 n = spectral_physical_gradient_hex(j, g_r);
    return length(n) > 0.0 ? normalize(n) : -d;
}

// A surface point of colour `colour` and unit normal n seen along d, Phong-lit (two-sided) by a
// light from −d + (0.2, 0.3, 0.5): how isosurfaces and sheets are shaded (twin:
// volume_reference's sheet colour).
vec3 spectral_ray_lit(vec3 colour, vec3 n, vec3 d) {
    return phong(colour, n, normalize(-d + vec3(0.2, 0.3, 0.5)), -d);
}
#endif
