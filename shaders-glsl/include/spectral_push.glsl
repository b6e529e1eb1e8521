// Push constants of the spectral draw pipelines (SpectralPush in src/spectral/render.rs).
#ifndef GALERKIN_SPECTRAL_PUSH_GLSL
#define GALERKIN_SPECTRAL_PUSH_GLSL
#define SPECTRAL_MODE_PER_PIXEL 0u
#define SPECTRAL_MODE_PER_VERTEX 1u
#define SPECTRAL_MODE_EDGE_OVERDRAW 2u
#define SPECTRAL_MODE_EDGE_LINES 3u
layout(push_constant) uniform SpectralPush {
    mat4 view_proj;
    // World (x, y) of framebuffer coordinate 0 and the world step per pixel along x and y.
    vec4 pixel_to_world;
    // Colour range lo, hi; ramp texels; iso-lines per range (0: none).
    vec4 range;
    // Normalised depth of this pass; reference-square tolerance of the inside test.
    vec4 misc;
    // Data output (raw values), log scale, mode (SPECTRAL_MODE_*), unused.
    uvec4 flags;
} pc;
#endif
