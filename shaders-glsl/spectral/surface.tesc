#version 450
// Adaptive tessellation of a curved surface element: an L × L grid of the reference square
// whose triangles lie within the screen-space error budget of the true surface.
//
// A right triangle with legs h = 1/L has circumradius R = h / sqrt(2), and linear interpolation
// at its vertices errs by at most R² / 2 · sup_u |D²_u x| (Waldron 1998) ≤ h² / 4 · K, where
// K = max(|x_ξξ|, |x_ηη|) + |x_ξη| bounds the directional second derivatives of the geometry
// map (from its Bernstein control net, src/spectral/proxy.rs). A world error e moves the image
// by at most e · P / z pixels (P: pixels per world unit at view depth 1, times the off-axis
// factor), z ≥ the element's nearest view depth. So L = ceil(sqrt(P K / (4 z budget))) keeps
// every tessellated point within `budget` pixels of the surface, up to the level cap.
#include "spectral_push.glsl"

layout(vertices = 1) out;
// Per element: (centre, radius) of a sphere containing it, (K, 0, 0, 0).
struct SpectralPatch { vec4 centre_radius; vec4 curvature; };
layout(std430, set = 0, binding = 4) readonly buffer Patches { SpectralPatch patches[]; };
layout(location = 0) patch out uint out_element;

void main() {
    SpectralPatch p = patches[gl_PrimitiveID];
    float depth = (pc.view_proj * vec4(p.centre_radius.xyz, 1.0)).w - p.centre_radius.w;
    float level;
    if (depth + 2.0 * p.centre_radius.w <= 0.0) {
        level = 0.0;  // wholly behind the eye: culled
    } else {
        float z = max(depth, 1e-3 * p.centre_radius.w);
        float pixels_per_unit = pc.pixel_to_world.w / z;
        level = clamp(ceil(sqrt(pixels_per_unit * p.curvature.x / (4.0 * pc.misc.z))), 1.0, pc.misc.w);
    }
    gl_TessLevelOuter[0] = level;
    gl_TessLevelOuter[1] = level;
    gl_TessLevelOuter[2] = level;
    gl_TessLevelOuter[3] = level;
    gl_TessLevelInner[0] = level;
    gl_TessLevelInner[1] = level;
    out_element = uint(gl_PrimitiveID);
}
