// Per-pixel strain energy density and exact height-field normal (seed 003 §4.2.3): the
// element's cubic, restricted to the slice time by the cut pass, is evaluated at the
// fragment's (x, y); U maps to the
// ramp by s = log(U + 1) / log(U_max + 1), the normal comes from the exact derivatives of |v|,
// and the colour is lit by Phong. The data output writes the raw values for EXR files and tests.
// With SPACETIME_EXPRESSION defined (a derived field, `--expr`, src/expression/spacetime.rs,
// compiled at run time), the expression of the slice's fields replaces U in the data output
// and the colour, mapped linearly from ramp.w (lo) to ramp.x (hi).
#ifndef GALERKIN_SPACETIME_SLICE_FRAG_GLSL
#define GALERKIN_SPACETIME_SLICE_FRAG_GLSL
#include "spacetime_cubic.glsl"
#include "colormap.glsl"
#include "phong.glsl"
#include "spacetime_push.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) in float vertex_s;
layout(location = 2) flat in uint el_index;
// The cut elements' cubics restricted to the slice's plane (written by slice.comp).
layout(std430, set = 0, binding = 3) readonly buffer Cubics { SpacetimeSliceCubic cubics[]; };
layout(set = 0, binding = 1) uniform sampler1D colormap;
layout(location = 0) out vec4 out_colour;

#ifdef SPACETIME_EXPRESSION
// The derived field at slice point p and time t: `spacetime_expression(values, gradients,
// variables)`, written by the run-time source before this file, reads the shown field |v|
// (slot 0, with its exact gradient) and the variables of expression::SPACETIME_VARIABLES.
// Twin of SpacetimeExpression::value_at (src/expression/spacetime.rs).
float spacetime_derived_value(SpacetimeFields f, vec2 p, float t) {
    float values[1] = float[1](f.speed);
    vec3 gradients[1] = vec3[1](vec3(f.speed_gradient, 0.0));
    vec3 variables[9] = vec3[9](vec3(p.x, 0.0, 0.0), vec3(p.y, 0.0, 0.0), vec3(t, 0.0, 0.0),
        vec3(f.strain_energy_density, 0.0, 0.0), vec3(f.velocity, 0.0), vec3(f.displacement, 0.0),
        vec3(f.strain.x, 0.0, 0.0), vec3(f.strain.y, 0.0, 0.0), vec3(f.strain.z, 0.0, 0.0));
    return spacetime_expression(values, gradients, variables);
}
#endif

void main() {
    if (pc.flags.x == 2u) {
        // Unshaded (SpacetimeView::unshaded): the draw's cost floor, nothing evaluated.
        out_colour = vec4(1.0);
        return;
    }
    SpacetimeFields f = spacetime_evaluate_slice(cubics[el_index], world.xy);
    // The height field's normal (at the height scale) is reported whether or not the surface
    // is displaced; lighting uses it only when it is (else the slice is flat).
    vec3 n = spacetime_normal(f, pc.light_scale.w);
#ifdef SPACETIME_EXPRESSION
    float shown = spacetime_derived_value(f, world.xy, pc.eye_t.w);
#else
    float shown = f.strain_energy_density;
#endif
    if (pc.flags.x == 1u) {
        out_colour = vec4(shown, f.speed, n.x, n.y);
        return;
    }
    if (pc.flags.y == 0u) n = vec3(0.0, 0.0, 1.0);
#ifdef SPACETIME_EXPRESSION
    float s = ramp_coordinate(shown, pc.ramp.w, pc.ramp.x, false);
#else
    float s = pc.flags.z != 0u
        ? vertex_s
        : ramp_coordinate(shown + 1.0, 1.0, pc.ramp.x + 1.0, true);
#endif
    vec3 colour = texture(colormap, ramp_texcoord(s, pc.ramp.y)).rgb;
    vec3 v = normalize(pc.eye_t.xyz - world);
    out_colour = vec4(phong(colour, n, pc.light_scale.xyz, v), 1.0);
}
#endif
