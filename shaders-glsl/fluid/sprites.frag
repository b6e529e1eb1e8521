#version 450
// A round sprite: colour by speed on the ramp (or white), or the raw speed and cell index
// with 1 in blue (OUTPUT_RAW = 1).
#include "push.glsl"
#include "colormap.glsl"

layout(constant_id = 0) const uint OUTPUT_RAW = 0;
layout(set = 0, binding = 0) uniform sampler1D colormap;

layout(location = 0) in vec2 v_corner;
layout(location = 1) flat in float v_value;
layout(location = 2) flat in uint v_cell;
layout(location = 0) out vec4 color;

void main() {
    if (dot(v_corner, v_corner) > 1.0) {
        discard;
    }
    if (OUTPUT_RAW == 1u) {
        color = vec4(v_value, float(v_cell), 1.0, 1.0);
        return;
    }
    if (pc.sprite.w != 0.0) {
        color = vec4(1.0);
        return;
    }
    float t = ramp_coordinate(v_value, pc.range.x, pc.range.y, pc.range.w != 0.0);
    color = vec4(texture(colormap, ramp_texcoord(t, pc.range.z)).rgb, 1.0);
}
