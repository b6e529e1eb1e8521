#version 450
#extension GL_EXT_control_flow_attributes : require
// Isosurfaces of a solid spectral element, per pixel, coloured by their values; the body, with
// its description, is spectral_iso_frag.glsl.
#include "spectral_iso_frag.glsl"
