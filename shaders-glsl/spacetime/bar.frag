#version 450
// Per-pixel strain energy density of the 1D bar (seed 003 Fig. 3c): the element's cubic at the
// fragment's (x, t), U = ½ (λ + 2μ) (∂u/∂x)² (plane strain with u_y = 0 and no y dependence),
// on the seed's log ramp. The data output writes (U, |v|, u, s): s the colour coordinate shown
// (per pixel, or interpolated from the vertices in the per-vertex mode).
#include "spacetime_cubic.glsl"
#include "colormap.glsl"
#include "spacetime_bar_push.glsl"

layout(location = 0) in vec2 frag_xt;
layout(location = 1) in float vertex_s;
layout(location = 2) flat in uint el_index;
layout(std430, set = 0, binding = 0) readonly buffer Elements { SpacetimeElement elements[]; };
layout(set = 0, binding = 1) uniform sampler1D colormap;
layout(location = 0) out vec4 out_colour;

void main() {
    SpacetimeFields f = spacetime_evaluate(elements[el_index], vec3(frag_xt.x, 0.0, frag_xt.y));
    float s = pc.flags.y != 0u
        ? vertex_s
        : ramp_coordinate(f.strain_energy_density + 1.0, 1.0, pc.ramp.x + 1.0, true);
    if (pc.flags.x == 1u) {
        out_colour = vec4(f.strain_energy_density, f.speed, f.displacement.x, s);
        return;
    }
    out_colour = vec4(texture(colormap, ramp_texcoord(s, pc.ramp.y)).rgb, 1.0);
}
