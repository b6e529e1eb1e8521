#version 450
// Cut planes through hexahedral spectral elements, pixel-exact; the body, with its
// description, is spectral_cut_frag.glsl (also compiled at run time with a derived field).
#include "spectral_cut_frag.glsl"
