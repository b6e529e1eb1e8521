#version 450
// Volume rendering (volume.frag): one triangle over the whole viewport; each fragment gets the
// homogeneous world point its pixel maps to on the far plane (the inverse view-projection,
// interpolated linearly: clip w is 1), the pixel's ray running from the eye through it.
#include "spectral_push.glsl"

layout(location = 0) out vec4 out_far;

void main() {
    vec2 p = vec2(float((gl_VertexIndex << 1) & 2), float(gl_VertexIndex & 2)) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.5, 1.0);
    out_far = inverse(pc.view_proj) * vec4(p, 1.0, 1.0);
}
