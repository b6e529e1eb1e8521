#version 450
// Colour from the ramp (OUTPUT_RAW = 0) or the raw value, cell index and kind (0 cell, 2
// surface) (OUTPUT_RAW = 1).
#include "push.glsl"
#include "colormap.glsl"

layout(constant_id = 0) const uint OUTPUT_RAW = 0;
layout(set = 0, binding = 0) uniform sampler1D colormap;

layout(location = 0) flat in float v_value;
layout(location = 1) flat in uint v_cell;
layout(location = 0) out vec4 color;

void main() {
    // pc.sprite.z: 0 plain cells, 1 cells on the ramp, 2 a shaded surface (value = shade).
    if (OUTPUT_RAW == 1u) {
        color = vec4(v_value, float(v_cell), pc.sprite.z == 2.0 ? 2.0 : 0.0, 1.0);
        return;
    }
    if (pc.sprite.z == 2.0) {
        color = vec4(vec3(0.80, 0.82, 0.88) * v_value, 1.0);
        return;
    }
    if (pc.sprite.z == 0.0) {
        color = vec4(0.78, 0.79, 0.82, 1.0);
        return;
    }
    float t = ramp_coordinate(v_value, pc.range.x, pc.range.y, pc.range.w != 0.0);
    color = vec4(texture(colormap, ramp_texcoord(t, pc.range.z)).rgb, 1.0);
}
