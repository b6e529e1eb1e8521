// Push constants of the spectral draw pipelines (SpectralPush in src/spectral/render.rs).
#ifndef GALERKIN_SPECTRAL_PUSH_GLSL
#define GALERKIN_SPECTRAL_PUSH_GLSL
#define SPECTRAL_MODE_PER_PIXEL 0u
#define SPECTRAL_MODE_PER_VERTEX 1u
#define SPECTRAL_MODE_EDGE_OVERDRAW 2u
#define SPECTRAL_MODE_EDGE_LINES 3u
#define SPECTRAL_PLANAR 0u
#define SPECTRAL_SURFACE 1u
layout(push_constant) uniform SpectralPush {
    mat4 view_proj;
    // Planar: world (x, y) of framebuffer coordinate 0 and the world step per pixel along x
    // and y. Surface: the eye (x, y, z) and pixels per world unit at view depth 1, for the
    // tessellation's screen-space error bound.
    vec4 pixel_to_world;
    // Colour range lo, hi; ramp texels; iso-lines per range (0: none).
    vec4 range;
    // Depth offset of this pass (planar: from 0.5; surface: added to clip z / w); the
    // reference-square tolerance of the inside test. Surface: the screen-space error budget in
    // pixels and the largest tessellation level. Planar: the viewport's corner in framebuffer
    // pixels (pixel_to_world maps pixels counted from it).
    vec4 misc;
    // Data output (raw values), log scale, mode (SPECTRAL_MODE_*), SPECTRAL_PLANAR or _SURFACE.
    uvec4 flags;
} pc;

// Clip position of world point x for this pass (with its depth offset).
vec4 spectral_clip(vec3 x) {
    vec4 clip = pc.view_proj * vec4(x, 1.0);
    if (pc.flags.w == SPECTRAL_PLANAR) clip.z = (0.5 + pc.misc.x) * clip.w;
    else clip.z += pc.misc.x * clip.w;
    return clip;
}
#endif
