#version 450
// Per-pixel strain energy density and exact height-field normal (seed 003 §4.2.3); the body,
// with its description, is spacetime_slice_frag.glsl (also compiled at run time with a
// derived field spliced in).
#include "spacetime_slice_frag.glsl"
