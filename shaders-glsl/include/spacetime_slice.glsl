// Bindings and push constants shared by the two slicing passes (spacetime/slice.comp,
// spacetime/subdivide.comp); Rust: SlicePushCompute in src/spacetime/render.rs.
#ifndef GALERKIN_SPACETIME_SLICE_GLSL
#define GALERKIN_SPACETIME_SLICE_GLSL
#include "spacetime_cubic.glsl"
// A slice vertex: position, element (in the window), |v| there (the height before scaling).
struct SliceVertex { vec2 xy; uint element; float speed; };
// The resident window of the records (a ring: the k-th active element is in slot
// (first + k) mod capacity) and the materials (λ, μ, ρ, 0).
layout(std430, set = 0, binding = 0) readonly buffer Records { SpacetimeRecord records[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { vec4 materials[]; };
// Two VkDrawIndirectCommand (triangles, lines), the overflow flag, the number of cut triangles.
layout(std430, set = 0, binding = 3) buffer Draws { uint draws[10]; };
layout(push_constant) uniform Push {
    uint first; uint count; float t; float max_area;
    uint max_level; uint tri_capacity; uint line_capacity; uint cut_capacity;
    uint capacity;   // records in the window's ring (record e in slot e mod capacity)
} pc;

// The slice restriction of every cut element (slot of the window's ring), written by the cut
// pass, read by the subdivision pass and the fragment stage.
layout(std430, set = 0, binding = 5) buffer Cubics { SpacetimeSliceCubic cubics[]; };

#endif
