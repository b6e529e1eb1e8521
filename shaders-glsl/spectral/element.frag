#version 450
// Pixel-exact spectral elements (seed 002, done per fragment) on surfaces; the body, with its
// description, is spectral_element_frag.glsl. Planar meshes use element_planar.frag, which adds
// the ownership rule at element edges.
#include "spectral_element_frag.glsl"
