#version 450
// Pixel-exact spectral elements on planar meshes: element.frag's body with the ownership rule
// at element edges (spectral_element_frag.glsl).
#define SPECTRAL_EDGE_OWNERSHIP
#include "spectral_element_frag.glsl"
