// Push constants of the 1D bar pipeline (src/spacetime/bar.rs, BarPush).
#ifndef GALERKIN_SPACETIME_BAR_PUSH_GLSL
#define GALERKIN_SPACETIME_BAR_PUSH_GLSL
layout(push_constant) uniform Push {
    vec4 window;   // x0, x1, t0, t1: the spacetime rectangle shown
    vec4 ramp;     // U_max, colour-map texels, 0, 0
    uvec4 flags;   // output (0: colour, 1: U, |v|, u, s), per-vertex colour, 0, 0
} pc;
#endif
