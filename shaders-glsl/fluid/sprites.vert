#version 450
// Particles as round sprites: six vertices per particle (two triangles of a square of
// pc.sprite.xy half-size in clip units), read from the particle buffer the compute pass wrote;
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

const vec2 CORNERS[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));

void main() {
    vec4 p = particles[gl_VertexIndex / 6];
    vec2 corner = CORNERS[gl_VertexIndex % 6];
    vec4 centre = pc.view_proj * vec4(p.xyz, 1.0);
    gl_Position = centre + vec4(corner * pc.sprite.xy * centre.w, 0.0, 0.0);
    v_corner = corner;
    v_cell = floatBitsToUint(p.w);
    v_value = PER_PARTICLE ? speed[gl_VertexIndex / 6] : speed[v_cell];
}
