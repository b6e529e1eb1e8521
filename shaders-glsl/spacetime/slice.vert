#version 450
// Time-slice polygons (seed 003 §4.2.2): the height |v| at each vertex (evaluated by the
// slicing passes) displaces it to (x, y, height_scale·|v|); the fragment stage reads its
// element's restricted cubic by the flat index (measured on lavapipe, Mesa 25: a per-fragment
// storage fetch draws twice as fast as passing an element's 48 values as flat varyings).
#include "spacetime_cubic.glsl"
#include "colormap.glsl"
#include "spacetime_push.glsl"

layout(location = 0) in vec2 xy;
layout(location = 1) in uint element;
layout(location = 2) in float speed;
layout(std430, set = 0, binding = 0) readonly buffer Records { SpacetimeRecord records[]; };
layout(std430, set = 0, binding = 2) readonly buffer Materials { vec4 materials[]; };   // λ, μ, ρ, 0

layout(location = 0) out vec3 world;
layout(location = 1) out float vertex_s;        // per-vertex colour coordinate (comparison mode)
layout(location = 2) flat out uint el_index;

void main() {
    float z = pc.flags.y != 0u ? pc.light_scale.w * speed : 0.0;
    world = vec3(xy, z);
    vertex_s = 0.0;
    if (pc.flags.z != 0u) {
        // Per-vertex colour (the comparison mode): U at the vertex.
        SpacetimeRecord r = records[element];
        SpacetimeElement el = spacetime_element(r, materials[floatBitsToUint(r.centre_material.w)]);
        SpacetimeFields f = spacetime_evaluate(el, vec3(xy, pc.eye_t.w));
        vertex_s = ramp_coordinate(f.strain_energy_density + 1.0, 1.0, pc.ramp.x + 1.0, true);
    }
    el_index = element;
    gl_Position = pc.view_proj * vec4(world, 1.0);
    // The edge pass sits behind the polygons (depth bias does not apply to lines): ramp.z is
    // EDGE_DEPTH_OFFSET of src/spacetime/render.rs there (normalised depth), 0 for polygons.
    gl_Position.z += pc.ramp.z * gl_Position.w;
}
