// Rays through solid elements, shared by the isosurface and volume passes (spectral_iso_frag.glsl,
// volume.frag): the slab test of an element's box and the retried pull-back of a point on the
// ray. Twins: iso_reference::slab and iso_reference::pull_back. Needs spectral_element.glsl
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
