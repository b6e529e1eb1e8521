// Per element, the surface tessellation's bounds (proxy.rs surface_patches/height_patches):
// (centre, radius of a sphere containing it), (K, height scale, 0, 0). A non-zero height scale
// lifts a planar element to the height field z = scale * f.
#ifndef GALERKIN_SPECTRAL_PATCHES_GLSL
#define GALERKIN_SPECTRAL_PATCHES_GLSL
struct SpectralPatch { vec4 centre_radius; vec4 curvature; };
layout(std430, set = 0, binding = 3) readonly buffer SpectralPatches { SpectralPatch patches[]; };
#endif
