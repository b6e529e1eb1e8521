#version 450
// The 1D bar of seed 003 Fig. 3: the whole spacetime (x, t) triangulation drawn as an image,
// x to the right and t upwards. Each vertex carries its element; the fragment stage evaluates
// the element's cubic per pixel. In the per-vertex comparison mode the colour coordinate is
// computed here at the vertices and interpolated (Fig. 3a).
#include "spacetime_cubic.glsl"
#include "colormap.glsl"
#include "spacetime_bar_push.glsl"

layout(location = 0) in vec2 xt;
layout(location = 1) in uint element;
layout(std430, set = 0, binding = 0) readonly buffer Elements { SpacetimeElement elements[]; };

layout(location = 0) out vec2 frag_xt;
layout(location = 1) out float vertex_s;
layout(location = 2) flat out uint el_index;

void main() {
    frag_xt = xt;
    el_index = element;
    vertex_s = 0.0;
    if (pc.flags.y != 0u) {
        SpacetimeFields f = spacetime_evaluate(elements[element], vec3(xt.x, 0.0, xt.y));
        vertex_s = ramp_coordinate(f.strain_energy_density + 1.0, 1.0, pc.ramp.x + 1.0, true);
    }
    vec2 s = (xt - pc.window.xz) / (pc.window.yw - pc.window.xz);
    gl_Position = vec4(2.0 * s.x - 1.0, 1.0 - 2.0 * s.y, 0.5, 1.0);
}
