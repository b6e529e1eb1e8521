#version 450
// Radiosity scene: one vertex per face corner with the radiance to show there (the face's,
// flat; or the vertex's average, smooth) and the face index for the raw output.
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 radiance;
layout(location = 2) in uint face;

layout(location = 0) out vec3 out_radiance;
layout(location = 1) flat out uint out_face;

layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 tone;   // x: exposure
} pc;

void main() {
    out_radiance = radiance;
    out_face = face;
    gl_Position = pc.view_proj * vec4(position, 1.0);
}
