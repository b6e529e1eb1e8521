#version 450
// Particles as round sprites: three vertices per particle, one triangle circumscribing the
// circle of radius pc.sprite.xy in clip units (the fragment shader discards outside it; one
// primitive a sprite instead of a square's two: a rasteriser's cost per primitive is most of
// a few-pixel sprite's), read from the particle buffer the compute pass wrote;
// coloured by the speed of the particle's cell (from the cells' speeds), or PER_PARTICLE by
// the speed the particle pass wrote for each particle (no full flux needed).
#include "push.glsl"

layout(constant_id = 1) const bool PER_PARTICLE = false;

layout(std430, set = 0, binding = 1) readonly buffer Particles { vec4 particles[]; };
// The cells' speeds, or PER_PARTICLE the particles'.
layout(std430, set = 0, binding = 2) readonly buffer Speeds { float speed[]; };

layout(location = 0) out vec2 v_corner;
layout(location = 1) flat out float v_value;
layout(location = 2) flat out uint v_cell;

// The equilateral triangle whose inscribed circle is the unit circle, counter-clockwise.
const vec2 CORNERS[3] = vec2[3](vec2(-1.7320508, -1.0), vec2(1.7320508, -1.0), vec2(0.0, 2.0));

void main() {
    uint particle = gl_VertexIndex / 3;
    vec4 p = particles[particle];
    vec2 corner = CORNERS[gl_VertexIndex % 3];
    vec4 centre = pc.view_proj * vec4(p.xyz, 1.0);
    gl_Position = centre + vec4(corner * pc.sprite.xy * centre.w, 0.0, 0.0);
    v_corner = corner;
    v_cell = floatBitsToUint(p.w);
    v_value = PER_PARTICLE ? speed[particle] : speed[v_cell];
}
