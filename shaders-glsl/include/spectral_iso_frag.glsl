#ifndef GALERKIN_SPECTRAL_ISO_FRAG_GLSL
#define GALERKIN_SPECTRAL_ISO_FRAG_GLSL
// Isosurfaces of a solid spectral element, per pixel (issue "isosurfaces and volume
// rendering"; ElVis's ray-element approach): the pixel's ray from the eye crosses the element's
// box between its entry (the slab test) and the box's far side where this fragment lies,
// clipped to the element's hull (spectral_ray_hull). The segment is sampled at SPECTRAL_ISO_SAMPLES points; at each the reference point is found by
// Newton's method warm-started from the previous one, and where the point lies inside the
// element (or within SPECTRAL_ISO_MARGIN of it, the polynomial continued) f − c is taken for
// every iso value c. Each sign change between two such samples is bisected in the ray
// parameter to f32 resolution (each step pulled back again), and the first root inside the
// element is drawn at its own depth, lit with the exact normal ∇f/|∇f| = J⁻ᵀ∇_r f/|·| and
// coloured by its iso value; with --edges, darkened where it meets its element's faces. Twin
// of reference::iso_reference (the f64 ray caster), which
// samples finer. Two roots between the same two samples (no sign change there) are caught where
// three samples' parabola turns toward zero between them (touching sheets, a surface the ray
// barely enters); closer pairs the parabola does not foresee are missed (no polynomial bounds
// of the field along the ray yet).
// The body of iso.frag and iso_colour.frag; the latter defines SPECTRAL_ISO_COLOUR_BY and two
// field slots: the roots are slot 0's, the colour is slot 1's value there (--colour-by).
#include "spectral_element.glsl"
// The element hulls' half-spaces (binding 5 of the isosurface draws).
#define SPECTRAL_HULL_BINDING 5
#include "spectral_ray.glsl"
#include "spectral_push.glsl"
#include "colormap.glsl"

layout(location = 1) flat in uint element;
layout(location = 3) in vec3 world;
layout(set = 0, binding = 2) uniform sampler1D colormap;
// Per element: (box lo, f lo), (box hi, f hi) — binding 3 of the spectral draws (iso.vert).
layout(std430, set = 0, binding = 3) readonly buffer Boxes { vec4 boxes[]; };
// The iso values: count, then the values.
layout(std430, set = 0, binding = 4) readonly buffer IsoValues { uint iso_count; float iso_values[]; };
layout(location = 0) out vec4 out_colour;
layout(depth_any) out float gl_FragDepth;

// Samples along each element's segment (the fragment stage's loop bound).
#define SPECTRAL_ISO_SAMPLES (8u + 4u * max(SPECTRAL_FIELD_ORDER, SPECTRAL_GEOMETRY_ORDER))

// How far outside its element (in reference units, spectral_outside_3d) a sample may lie and
// still bracket roots, with the field's polynomial continued there: a root near a face then
// sits between two usable samples; roots found outside the element are left to its neighbour.
#define SPECTRAL_ISO_MARGIN 0.25

// Element edges on the surface (--edges): a surface point within this many pixels of a face of
// its element, measured along the surface, is darkened — the curves where the isosurface crosses
// the element faces, about two pixels wide (one on each side of a shared face).
#define SPECTRAL_ISO_EDGE_PX 1.0

// How far, in world units along the surface of unit normal n, a reference coordinate at
// distance delta from its face (physical gradient g) lies from it: delta / |g - (g.n) n|.
float iso_along_surface(float delta, vec3 g, vec3 n) {
    vec3 gt = g - dot(g, n) * n;
    float len = length(gt);
    return len > 0.0 ? max(delta, 0.0) / len : 1e30;
}

// The distance in pixels, along the surface, from the point at reference r (Jacobian j, unit
// normal n, view depth `depth`) to the nearest face of its element: each face's reference
// coordinate (r_a or 1 - r_a; 1 - r.x - r.y - r.z on a tetrahedron's slanted face) over the
// tangential part of its physical gradient (J^-T e_a), in pixels of world size depth / focal.
// Twin of iso_reference::face_distance_px.
float iso_face_distance_px(mat3 j, vec3 r, vec3 n, float depth) {
    // Column a of J^-T is the physical gradient of r_a (spectral_physical_gradient_hex of e_a).
    mat3 gradients = transpose(inverse(j));
    float best = 1e30;
    for (uint a = 0u; a < 3u; ++a) {
        float delta = SPECTRAL_SIMPLEX ? r[a] : min(r[a], 1.0 - r[a]);
        best = min(best, iso_along_surface(delta, gradients[a], n));
    }
    if (SPECTRAL_SIMPLEX) {
        vec3 g = gradients[0] + gradients[1] + gradients[2];
        best = min(best, iso_along_surface(1.0 - r.x - r.y - r.z, g, n));
    }
    return best * pc.pixel_to_world.w / depth;
}

void main() {
    vec3 eye = pc.pixel_to_world.xyz;
    vec3 d = normalize(world - eye);
    float t_exit = dot(world - eye, d);
    vec3 lo = boxes[2u * element].xyz, hi = boxes[2u * element + 1u].xyz;
    vec2 crossing = spectral_ray_box(eye, d, lo, hi);
    float t_entry = crossing.x, t_far = crossing.y;
    // Only the box's far side casts (both sides are drawn: the eye may be inside a box).
    if (!(t_entry < t_exit) || t_exit - t_entry < 0.5 * (t_far - t_entry)) discard;
    // Sampled only where the ray lies in the element's hull (most of a tetrahedron's box is
    // outside it).
    vec2 span = spectral_ray_hull(element, eye, d, vec2(t_entry, t_exit));
    if (!(span.x < span.y)) discard;
    t_entry = span.x;
    t_exit = span.y;
    uint count = min(iso_count, 8u);
    vec3 r = vec3(SPECTRAL_SIMPLEX ? 0.25 : 0.5);
    float step_t = (t_exit - t_entry) / float(SPECTRAL_ISO_SAMPLES);
    // The last two usable samples: g = f - c per value, their ray parameters and reference
    // points.
    bool usable_prev = false, usable_prev2 = false;
    float g_prev[8], g_prev2[8];
    float t_prev = t_entry, t_prev2 = t_entry;
    vec3 r_prev = r, r_prev2 = r;
    bool found = false;
    uint hit_k = 0u;
    float t_root = 0.0;
    vec3 r_root = r;
    for (uint s = 0u; s <= SPECTRAL_ISO_SAMPLES && !found; ++s) {
        float t = t_entry + float(s) * step_t;
        bool usable = spectral_pull_hex(element, eye + t * d, r) && spectral_outside_3d(r) <= SPECTRAL_ISO_MARGIN;
        if (usable) {
            float f = spectral_value_hex(element, r);
            // The value crossed first in this interval (linear estimate), if any.
            float best = 2.0;
            uint k_best = 0u;
            for (uint k = 0u; k < count; ++k) {
                float g = f - iso_values[k];
                if (usable_prev && (g_prev[k] < 0.0) != (g < 0.0)) {
                    float frac = g_prev[k] / (g_prev[k] - g);
                    if (frac < best) {
                        best = frac;
                        k_best = k;
                    }
                }
            }
            // A pair of roots between samples (a surface the ray barely enters, or two sheets
            // that touch): three samples of one sign whose parabola turns toward zero between
            // them and reaches it, or nearly (a quarter of the smallest sample); the value at
            // the parabola's turning point is then taken, and a sign there brackets the pair's
            // first root.
            float pair_lo = 0.0, pair_hi = 0.0, pair_g = 0.0;
            uint pair_k = 0u;
            bool pair = false;
            vec3 pair_r = r_prev2;
            for (uint k = 0u; k < count && usable_prev && usable_prev2 && !pair; ++k) {
                float a0 = g_prev2[k], a1 = g_prev[k], a2 = f - iso_values[k];
                float sgn = a1 < 0.0 ? -1.0 : 1.0;
                if (a0 * sgn <= 0.0 || a2 * sgn <= 0.0) continue;
                // p(u) = a0 + B u + A u², u in sample intervals from t_prev2.
                float A = 0.5 * (a0 - 2.0 * a1 + a2), B = 0.5 * (4.0 * a1 - 3.0 * a0 - a2);
                if (A * sgn <= 0.0) continue;
                float u = -B / (2.0 * A);
                if (!(u > 0.0 && u < 2.0)) continue;
                float q = a0 + u * (B + A * u);
                if (q * sgn >= 0.25 * min(abs(a0), min(abs(a1), abs(a2)))) continue;
                float tv = t_prev2 + u * step_t;
                bool later = u >= 1.0;
                vec3 rv = later ? r_prev : r_prev2;
                if (!spectral_pull_hex(element, eye + tv * d, rv) || spectral_outside_3d(rv) > SPECTRAL_ISO_MARGIN) continue;
                if ((spectral_value_hex(element, rv) - iso_values[k]) * sgn < 0.0) {
                    pair = true;
                    pair_k = k;
                    pair_lo = later ? t_prev : t_prev2;
                    pair_hi = tv;
                    pair_g = later ? a1 : a0;
                    pair_r = later ? r_prev : r_prev2;
                }
            }
            // Bisect the candidates; the nearest root inside the element is the pixel's.
            if (pair) {
                vec3 q = pair_r;
                float tr = spectral_ray_bisect(element, eye, d, pair_lo, pair_hi, iso_values[pair_k], pair_g, q);
                if (spectral_outside_3d(q) <= pc.misc.y) {
                    found = true;
                    hit_k = pair_k;
                    t_root = tr;
                    r_root = q;
                }
            }
            if (best <= 1.0 && !(found && t_root <= t_prev)) {
                vec3 q = r_prev;
                float tr = spectral_ray_bisect(element, eye, d, t_prev, t, iso_values[k_best], g_prev[k_best], q);
                // A root outside the element is its neighbour's.
                if (spectral_outside_3d(q) <= pc.misc.y && !(found && t_root <= tr)) {
                    found = true;
                    hit_k = k_best;
                    t_root = tr;
                    r_root = q;
                }
            }
            for (uint k = 0u; k < count; ++k) {
                g_prev2[k] = g_prev[k];
                g_prev[k] = f - iso_values[k];
            }
        }
        usable_prev2 = usable && usable_prev;
        usable_prev = usable;
        t_prev2 = t_prev;
        r_prev2 = r_prev;
        t_prev = t;
        r_prev = r;
    }
    if (!found) discard;
    float c = iso_values[hit_k];
    vec3 x_root = eye + t_root * d;
    vec3 rr = spectral_clamp_3d(r_root);
    vec4 clip = pc.view_proj * vec4(x_root, 1.0);
    gl_FragDepth = clip.z / clip.w;
    vec4 fg = spectral_slot_value_gradient_hex(element, 0u, rr);
#ifdef SPECTRAL_ISO_COLOUR_BY
    float shown = spectral_value_hex_slot(element, 1u, rr);
#else
    float shown = c;
#endif
    if (pc.flags.x != 0u) {
        // Data: the value at the root (with --colour-by, the colouring field's), its distance
        // from the eye, the iso value's index, the element.
#ifdef SPECTRAL_ISO_COLOUR_BY
        out_colour = vec4(shown, t_root, float(hit_k), float(element));
#else
        out_colour = vec4(fg.x, t_root, float(hit_k), float(element));
#endif
        return;
    }
    mat3 j;
    spectral_map_hex(element, rr, j);
    vec3 n = spectral_level_normal(j, fg.yzw, d);
    float tc = ramp_coordinate(shown, pc.range.x, pc.range.y, pc.flags.y != 0u);
    vec3 colour = texture(colormap, ramp_texcoord(tc, pc.range.z)).rgb;
    vec3 shaded = spectral_ray_lit(colour, n, d);
    if (pc.flags.z != 0u && iso_face_distance_px(j, rr, n, clip.w) <= SPECTRAL_ISO_EDGE_PX) shaded *= 0.2;
    out_colour = vec4(shaded, 1.0);
}
#endif
