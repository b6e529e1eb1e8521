// Bindings and push constants shared by the two slicing passes (spacetime/slice.comp,
// spacetime/subdivide.comp); Rust: SlicePushCompute in src/spacetime/render.rs.
#ifndef GALERKIN_SPACETIME_SLICE_GLSL
#define GALERKIN_SPACETIME_SLICE_GLSL
struct SliceVertex { vec2 xy; uint element; float pad; };
// Two VkDrawIndirectCommand (triangles, lines), the overflow flag, the number of cut triangles.
layout(std430, set = 0, binding = 3) buffer Draws { uint draws[10]; };
layout(push_constant) uniform Push {
    uint first; uint count; float t; float max_area;
    uint max_level; uint tri_capacity; uint line_capacity; uint cut_capacity;
} pc;
#endif
