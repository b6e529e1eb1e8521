// The body of element.frag and element_planar.frag (see element.frag).
// Pixel-exact spectral elements (seed 002, done per fragment).
// Planar: the fragment's world point is taken from its pixel centre, Newton's method on the
// element's geometry map finds the reference point (xi, eta) that maps there (starting from the
// interpolated proxy coordinates), fragments whose point leaves the reference square (or
// triangle) are discarded — so curved edges are exact — and the element's tensor-product polynomial is
// evaluated there and colour-mapped.
// Surface: the reference point is the one interpolated across the adaptively tessellated
// element (within the error budget of the true surface on screen); the value is evaluated
// there, and lit with the exact normal of the geometry map at that point.
// Iso-lines of constant on-screen width come from the per-pixel value and its screen derivatives.
// With SPECTRAL_EXPRESSION defined (a derived field, src/expression) the value shown is the
// expression's, evaluated per pixel from the element's exact polynomials.
#include "spectral_element.glsl"
#include "spectral_push.glsl"
#include "colormap.glsl"
#include "phong.glsl"
#include "spectral_patches.glsl"

layout(location = 0) in vec2 in_reference;
layout(location = 1) flat in uint element;
layout(location = 2) in float vertex_value;
layout(location = 3) in vec3 world;
layout(location = 4) flat in vec4 coefficients[SPECTRAL_FLAT_VEC4S];
layout(set = 0, binding = 2) uniform sampler1D colormap;
layout(location = 0) out vec4 out_colour;
#ifdef SPECTRAL_EDGE_OWNERSHIP
// Ownership at element edges (planar meshes, `element_planar.frag`): a fragment lies deeper by
// how far its reference point is outside [0, 1]² (at most the inside tolerance, 1e-5: far less
// than the edge passes' offsets of 0.25), so where two elements both accept a pixel centre the
// one that contains it wins whatever the draw order; exact ties (a centre on the edge to f32
// rounding) go to the later. Surfaces do without: writing the depth costs them about 40 % of
// their frame time on lavapipe (BENCHMARKS.md), and their pixels are owned by depth anyway.
layout(depth_greater) out float gl_FragDepth;
#endif

void main() {
    uint mode = pc.flags.z;
    bool surface = pc.flags.w == SPECTRAL_SURFACE;
    vec2 r = in_reference;
    bool inside = true;
    float outside = 0.0;
    if (mode == SPECTRAL_MODE_PER_PIXEL && !surface) {
        vec2 p = pc.pixel_to_world.xy + (gl_FragCoord.xy - pc.misc.zw) * pc.pixel_to_world.zw;
        float tol = pc.misc.y;
        inside = spectral_inverse_map(element, p, r) && spectral_outside(r) <= tol;
        outside = max(0.0, spectral_outside(r));
    }
#ifdef SPECTRAL_EDGE_OWNERSHIP
    gl_FragDepth = gl_FragCoord.z + outside;
#endif
    r = spectral_clamp(r);
    // A surface fragment is lit with the geometry's tangents, evaluated with the value (the
    // data output takes the same path, so the tests check the code that draws the colours).
    bool lit = surface && mode != SPECTRAL_MODE_EDGE_LINES;
    vec3 x, dxi, deta;
    float v;
#ifdef SPECTRAL_EXPRESSION
    // A derived field (`--expr`, compiled at run time): the expression of every slot's value
    // and physical gradient at r is the value (per-vertex colour is refused on the host).
    v = spectral_derived_value(element, r);
    if (lit) x = spectral_map(element, r, dxi, deta);
#else
    if (mode == SPECTRAL_MODE_PER_VERTEX) {
        v = vertex_value;
        if (lit) x = spectral_map(element, r, dxi, deta);
    } else if (lit) {
        v = spectral_value_and_map(element, r, coefficients, x, dxi, deta);
    } else {
        v = spectral_value_given(element, r, coefficients);
    }
#endif
    float t = ramp_coordinate(v, pc.range.x, pc.range.y, pc.flags.y != 0u);
    // Iso-lines: distance to the nearest level in pixels from the screen derivative of the
    // level coordinate (taken before any discard, while the whole quad is live).
    float levels = t * pc.range.w;
    float width = fwidth(levels);
    if (!inside) discard;
    if (pc.flags.x != 0u) {
        // Edge overdraw marks its pixels with −(element + 1) so analyses can tell them apart.
        out_colour = vec4(v, r, mode >= SPECTRAL_MODE_EDGE_OVERDRAW ? -float(element) - 1.0 : float(element));
        return;
    }
    vec3 colour = texture(colormap, ramp_texcoord(t, pc.range.z)).rgb;
    if (mode == SPECTRAL_MODE_EDGE_LINES) colour = vec3(0.05);
    // Interior levels only: the range's ends would ring the extrema.
    float nearest = floor(levels + 0.5);
    if (pc.range.w > 0.0 && width > 0.0 && nearest > 0.0 && nearest < pc.range.w) {
        float d = abs(levels - nearest) / width;
        colour = mix(colour, vec3(0.0), 0.8 * (1.0 - clamp(d - 0.5, 0.0, 1.0)));
    }
    if (lit) {
        float height = patches[element].curvature.y;
        if (height != 0.0) {
            // The height field's exact normal: the tangents lifted by scale * (f_xi, f_eta).
            vec3 g = spectral_value_gradient(element, r);
            dxi.z += height * g.y;
            deta.z += height * g.z;
        }
        vec3 n = normalize(cross(dxi, deta));
        vec3 view = normalize(pc.pixel_to_world.xyz - world);
        vec3 light = normalize(view + vec3(0.2, 0.3, 0.5));
        colour = phong(colour, n, light, view);
    }
    out_colour = vec4(colour, 1.0);
}
