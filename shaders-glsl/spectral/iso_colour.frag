#version 450
#extension GL_EXT_control_flow_attributes : require
// Isosurfaces of a solid spectral element, per pixel, coloured by a second field (--colour-by):
// two coefficient slots per element, the roots of slot 0, the colour of slot 1's value there.
// The body, with its description, is spectral_iso_frag.glsl.
#define SPECTRAL_FIELDS 2u
#define SPECTRAL_ISO_COLOUR_BY
#include "spectral_iso_frag.glsl"
