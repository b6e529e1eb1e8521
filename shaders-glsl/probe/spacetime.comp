#version 450
// Test probe: evaluates include/spacetime_cubic.glsl and include/phong.glsl at given inputs so
// tests can compare them with their Rust twins (spacetime/cubic.rs, render/phong.rs).
#include "spacetime_cubic.glsl"
#include "phong.glsl"

layout(local_size_x = 64) in;
layout(std430, set = 0, binding = 0) readonly buffer Records { SpacetimeRecord records[]; };
layout(std430, set = 0, binding = 4) readonly buffer Materials { vec4 materials[]; };
// Per probe: (x, y, t, element) and a Phong input set: colour, normal, light, eye (vec4 each).
layout(std430, set = 0, binding = 1) readonly buffer Points { vec4 points[]; };
layout(std430, set = 0, binding = 2) readonly buffer PhongIn { vec4 phong_in[]; };
// Per probe: (U, |v|, ∂|v|/∂x, ∂|v|/∂y), (v_x, v_y, ε_xx, ε_yy), (ε_xy, n_x, n_y, n_z),
// (u_x, u_y, 0, 0), (phong rgb, 0), (U, |v|, ∂|v|/∂x, ∂|v|/∂y) through the slice restriction.
layout(std430, set = 0, binding = 3) writeonly buffer Out { vec4 result[]; };
layout(push_constant) uniform Push { uint n; float height_scale; } pc;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.n) return;
    vec4 p = points[i];
    SpacetimeRecord r = records[uint(p.w)];
    SpacetimeFields f = spacetime_evaluate(spacetime_element(r, materials[floatBitsToUint(r.centre_material.w)]), p.xyz);
    vec3 nrm = spacetime_normal(f, pc.height_scale);
    result[6u * i + 0u] = vec4(f.strain_energy_density, f.speed, f.speed_gradient);
    result[6u * i + 1u] = vec4(f.velocity, f.strain.xy);
    result[6u * i + 2u] = vec4(f.strain.z, nrm);
    result[6u * i + 3u] = vec4(f.displacement, 0.0, 0.0);
    vec3 lit = phong(phong_in[4u * i].rgb, normalize(phong_in[4u * i + 1u].xyz),
                     normalize(phong_in[4u * i + 2u].xyz), normalize(phong_in[4u * i + 3u].xyz));
    result[6u * i + 4u] = vec4(lit, 0.0);
    // The same fields through the slice restriction at p.t.
    SpacetimeFields g = spacetime_evaluate_slice(
        spacetime_restrict(spacetime_element(r, materials[floatBitsToUint(r.centre_material.w)]), p.z), p.xy);
    result[6u * i + 5u] = vec4(g.strain_energy_density, g.speed, g.speed_gradient);
}
