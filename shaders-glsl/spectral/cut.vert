#version 450
// The section rectangles of cut.comp: positions through the camera, the plane index and the
// element passed on, the world point interpolated for cut.frag's Newton pull-back.
#include "spectral_push.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec2 plane;
layout(location = 2) in uint element;
layout(location = 0) out vec2 out_plane;
layout(location = 1) flat out uint out_element;
layout(location = 3) out vec3 out_world;

void main() {
    gl_Position = spectral_clip(position);
    out_plane = plane;
    out_element = element;
    out_world = position;
}
