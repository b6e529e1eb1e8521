#version 450
// Radiosity scene: tone-mapped colour (OUTPUT_RAW = 0, to an 8-bit target) or the raw
// radiance and face index (OUTPUT_RAW = 1, to a float target: EXR files and tests).
#include "tonemap.glsl"

layout(constant_id = 0) const uint OUTPUT_RAW = 0;

layout(location = 0) in vec3 radiance;
layout(location = 1) flat in uint face;
layout(location = 0) out vec4 color;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 tone;   // x: exposure
} pc;

void main() {
    if (OUTPUT_RAW == 1u) {
        color = vec4(radiance, float(face));
    } else {
        color = vec4(tone_map(radiance, pc.tone.x), 1.0);
    }
}
