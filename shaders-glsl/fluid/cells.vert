#version 450
// Fluid cells (2D): each triangle carries its cell's speed |u_c| (constant per cell, as the
// method assumes) and its index.
#include "push.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in float value;
layout(location = 2) in uint cell;
layout(location = 0) flat out float v_value;
layout(location = 1) flat out uint v_cell;

void main() {
    gl_Position = pc.view_proj * vec4(position, 1.0);
    v_value = value;
    v_cell = cell;
}
