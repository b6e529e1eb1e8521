#version 450
// Isosurfaces (iso.frag): each solid element's box (the box of its Bernstein control points,
// which contains it), drawn with its front faces culled, so every pixel the element may cover
// gets one fragment on the box's far side — where the ray leaves the box. An element whose
// value bounds (the least and greatest Bernstein coefficient of its field, in the boxes' fourth
// components: proxy::value_bounds) hold no iso value cannot contain a root: its box is clipped.
#include "spectral_push.glsl"

// Per element: (box lo, f lo), (box hi, f hi).
layout(std430, set = 0, binding = 3) readonly buffer Boxes { vec4 boxes[]; };
layout(std430, set = 0, binding = 4) readonly buffer IsoValues { uint iso_count; float iso_values[]; };

layout(location = 0) in vec3 position;
layout(location = 1) in vec2 unused_reference;
layout(location = 2) in uint element;
layout(location = 1) flat out uint out_element;
layout(location = 3) out vec3 out_world;

void main() {
    float f_lo = boxes[2u * element].w, f_hi = boxes[2u * element + 1u].w;
    bool holds = false;
    for (uint k = 0u; k < min(iso_count, 8u); ++k) {
        holds = holds || (iso_values[k] >= f_lo && iso_values[k] <= f_hi);
    }
    // Outside the clip volume (z > w): no fragment.
    gl_Position = holds ? spectral_clip(position) : vec4(0.0, 0.0, 2.0, 1.0);
    out_element = element;
    out_world = position;
}
