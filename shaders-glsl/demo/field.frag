#version 450
// Demo field pass: evaluates the cubic at the fragment's world position (perspective-correct
// interpolation gives the point of the plane seen through the pixel centre) and writes either
// the raw value (OUTPUT_VALUE, to a float target) or its colour through the ramp texture.
#include "polynomial.glsl"
#include "colormap.glsl"

layout(constant_id = 0) const uint OUTPUT_VALUE = 1;

layout(location = 0) in vec2 world_xy;
layout(location = 0) out vec4 color;

layout(std140, set = 0, binding = 0) uniform Field {
    vec4 coefficients[3];   // c00 .. c03 packed four per vec4
    vec4 ramp;              // lo, hi, log (0 or 1), texel count
} field;
layout(set = 0, binding = 1) uniform sampler1D colormap;

void main() {
    float c[10];
    for (int k = 0; k < 10; ++k) {
        c[k] = field.coefficients[k / 4][k % 4];
    }
    float p = bivariate_cubic(c, world_xy);
    if (OUTPUT_VALUE == 1u) {
        color = vec4(p, world_xy, 1.0);
    } else {
        float t = ramp_coordinate(p, field.ramp.x, field.ramp.y, field.ramp.z > 0.5);
        color = vec4(texture(colormap, ramp_texcoord(t, field.ramp.w)).rgb, 1.0);
    }
}
