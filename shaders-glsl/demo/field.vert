#version 450
// Demo field pass: triangles on the plane z = 0; the fragment stage gets the world position.
layout(location = 0) in vec3 position;
layout(location = 0) out vec2 world_xy;
layout(push_constant) uniform Push { mat4 view_proj; } pc;

void main() {
    world_xy = position.xy;
    gl_Position = pc.view_proj * vec4(position, 1.0);
}
