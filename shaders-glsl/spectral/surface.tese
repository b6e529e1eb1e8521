#version 450
// The tessellated surface element: each generated vertex is the exact geometry map at its
// reference coordinates (gl_TessCoord), which the fragment stage receives interpolated.
#include "spectral_element.glsl"
#include "spectral_push.glsl"

layout(quads, equal_spacing, ccw) in;
layout(location = 0) patch in uint element;
layout(location = 0) out vec2 out_reference;
layout(location = 1) flat out uint out_element;
layout(location = 2) out float out_value;
layout(location = 3) out vec3 out_world;

void main() {
    vec2 r = gl_TessCoord.xy;
    vec3 dxi, deta;
    vec3 x = spectral_map(element, r, dxi, deta);
    gl_Position = spectral_clip(x);
    out_reference = r;
    out_element = element;
    out_value = 0.0;
    out_world = x;
}
