// The section of a hexahedral spectral element by a cut plane, pixel-exact: the fragment's
// point on the plane (interpolated across the bounding rectangle cut.comp drew) is pulled back
// by Newton's method in (xi, eta, zeta); points outside the reference cube (or tetrahedron) are
// discarded, so
// the section's curved outline is exact; the element's polynomial is evaluated there,
// colour-mapped and lit with the plane's normal.
//
// Ownership at element faces: where two elements' rectangles overlap, both may accept a point
// within the inside tolerance (1e-5) of their common face. The fragment lies deeper by how far
// its reference point is outside the reference element (spectral_outside_3d), so the element that contains the point wins whatever
// the draw order (the rule of element_planar.frag's edges; a cut plane's fragments are few, so
// writing the depth costs little here).
// With SPECTRAL_EXPRESSION defined (a derived field, src/expression, compiled at run time) the
// value shown is the expression's (spectral_derived_value_hex).
#ifndef GALERKIN_SPECTRAL_CUT_FRAG_GLSL
#define GALERKIN_SPECTRAL_CUT_FRAG_GLSL
#include "spectral_element.glsl"
#include "spectral_push.glsl"
#include "colormap.glsl"
#include "phong.glsl"

layout(location = 0) in vec2 in_reference;
layout(location = 1) flat in uint element;
layout(location = 3) in vec3 world;
layout(set = 0, binding = 2) uniform sampler1D colormap;
layout(std430, set = 0, binding = 3) readonly buffer Planes { vec4 planes[]; };
layout(location = 0) out vec4 out_colour;
layout(depth_greater) out float gl_FragDepth;

void main() {
    uint plane = uint(in_reference.x + 0.5);
    // Newton from the element's centre: (1/2)^3 on the cube, (1/4)^3 on the tetrahedron.
    vec3 r = vec3(SPECTRAL_SIMPLEX ? 0.25 : 0.5);
    float tol = pc.misc.y;
    bool inside = spectral_inverse_map_hex(element, world, r) && spectral_outside_3d(r) <= tol;
    gl_FragDepth = gl_FragCoord.z + max(spectral_outside_3d(r), 0.0);
    r = spectral_clamp_3d(r);
#ifdef SPECTRAL_EXPRESSION
    float v = spectral_derived_value_hex(element, r);
#else
    float v = spectral_value_hex(element, r);
#endif
    float t = ramp_coordinate(v, pc.range.x, pc.range.y, pc.flags.y != 0u);
    float levels = t * pc.range.w;
    float width = fwidth(levels);
    if (!inside) discard;
    if (pc.flags.x != 0u) {
        out_colour = vec4(v, float(plane), r.z, float(element));
        return;
    }
    vec3 colour = texture(colormap, ramp_texcoord(t, pc.range.z)).rgb;
    float nearest = floor(levels + 0.5);
    if (pc.range.w > 0.0 && width > 0.0 && nearest > 0.0 && nearest < pc.range.w) {
        float d = abs(levels - nearest) / width;
        colour = mix(colour, vec3(0.0), 0.8 * (1.0 - clamp(d - 0.5, 0.0, 1.0)));
    }
    vec3 view = normalize(pc.pixel_to_world.xyz - world);
    vec3 light = normalize(view + vec3(0.2, 0.3, 0.5));
    out_colour = vec4(phong(colour, planes[plane].xyz, light, view), 1.0);
}
#endif
