#version 450
// Isosurfaces (iso.frag): each solid element's box (the box of its Bernstein control points,
// which contains it), drawn with its front faces culled, so every pixel the element may cover
// gets one fragment on the box's far side — where the ray leaves the box.
#include "spectral_push.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec2 unused_reference;
layout(location = 2) in uint element;
layout(location = 1) flat out uint out_element;
layout(location = 3) out vec3 out_world;

void main() {
    gl_Position = spectral_clip(position);
    out_element = element;
    out_world = position;
}
