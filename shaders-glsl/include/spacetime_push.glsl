// Push constants of the spacetime slice pipelines (src/spacetime/render.rs, SlicePush).
#ifndef GALERKIN_SPACETIME_PUSH_GLSL
#define GALERKIN_SPACETIME_PUSH_GLSL
layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 eye_t;         // eye position, time of the slice
    vec4 light_scale;   // unit direction to the light, height scale
    vec4 ramp;          // U_max, colour-map texels, depth offset (edge pass), 0
    uvec4 flags;        // output (0: lit colour, 1: U, |v|, n_x, n_y, 2: one constant colour),
                        // height on, per-vertex colour, 0
} pc;
#endif
