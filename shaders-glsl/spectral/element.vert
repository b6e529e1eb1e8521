#version 450
// Spectral element proxies, per-vertex node grids and edge lines (seed 002): positions through
// the view, the reference coordinates (and for low orders the element's coefficients) passed on
// for the fragment stage; in per-vertex mode the field is evaluated here, at the node, and
// interpolated (the seed's baseline).
#include "spectral_element.glsl"
#include "spectral_push.glsl"
#include "spectral_patches.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec2 reference;
layout(location = 2) in uint element;
layout(location = 0) out vec2 out_reference;
layout(location = 1) flat out uint out_element;
layout(location = 2) out float out_value;
layout(location = 3) out vec3 out_world;
// Per pixel, the element's coefficients for the fragment stage (SPECTRAL_FLAT_VALUES).
layout(location = 4) flat out vec4 out_coefficients[SPECTRAL_FLAT_VEC4S];

void main() {
    // Height fields lift every vertex (tessellated or on an edge line) to z = scale * f.
    vec3 x = position;
    float height = patches[element].curvature.y;
    if (pc.flags.w == SPECTRAL_SURFACE && height != 0.0) x.z = height * spectral_value(element, reference);
    gl_Position = spectral_clip(x);
    out_reference = reference;
    out_element = element;
    out_value = pc.flags.z == SPECTRAL_MODE_PER_VERTEX ? spectral_value(element, reference) : 0.0;
    out_world = x;
    if (pc.flags.z == SPECTRAL_MODE_PER_VERTEX) {
        for (uint q = 0u; q < SPECTRAL_FLAT_VEC4S; ++q) out_coefficients[q] = vec4(0.0);
    } else {
        spectral_flat_coefficients(element, out_coefficients);
    }
}
