#version 450
// Volume rendering of a solid spectral mesh, per pixel (issue "isosurfaces and volume
// rendering"; ElVis's ray-element approach): emission–absorption along the pixel's ray,
// C = ∫ c(f) σ(f) e^{−∫σ} dt and T = e^{−∫σ dt}, with c the colour map and σ the transfer
// function's extinction (spectral::transfer). The ray meets the elements its screen tile lists
// (binned on the host, volume.rs); for each whose box it crosses, the crossing (clipped to the
// element's hull: spectral_ray_hull) is sampled at
// SPECTRAL_VOLUME_SAMPLES points pulled back by warm-started Newton, the element's entry and
// exit bisected to f32 resolution where the samples go in or out (or, between two samples
// outside, where the chord joining their reference points crosses the reference element and
// the ray's point there is inside: a corner or edge clipped), and the part inside
// integrated interval by interval: each interval is split where the field (linear between
// its ends) crosses an opacity point of the transfer function, and each piece integrated by
// the midpoint rule in SPECTRAL_VOLUME_SUBSTEPS sub-steps with the field evaluated exactly at
// each midpoint and the exponential exact (a − e^{−σΔ} per step). The elements' parts, each
// composited on its own, are sorted by where the ray enters them (elements do not overlap, so
// this is the ray's order) and combined front to back; a ray meeting more than
// SPECTRAL_VOLUME_SLOTS elements takes further rounds, each the next slots beyond the last.
// Isosurfaces drawn here (transparent ones, or isosurfaces in a volume) are sheets: within each
// interval inside an element, every sheet value c that f − c changes sign for is bisected to
// its root, the roots are taken in ray order, and at each the sheet — the colour map at c, lit
// with the exact normal J⁻ᵀ∇_r f/|·| — is composited with its opacity α (C += T α c, T *= 1 − α),
// the volume integrated between them.
// Twin of spectral::volume_reference (the f64 ray caster), which samples finer.
#extension GL_EXT_control_flow_attributes : require
#include "spectral_element.glsl"
// The element hulls' half-spaces (binding 6).
#define SPECTRAL_HULL_BINDING 6
#include "spectral_ray.glsl"
#include "spectral_push.glsl"
#include "colormap.glsl"

layout(location = 0) in vec4 far_point;
layout(set = 0, binding = 2) uniform sampler1D colormap;
// Per element: (box lo, f lo), (box hi, f hi) — as iso.vert's.
layout(std430, set = 0, binding = 3) readonly buffer Boxes { vec4 boxes[]; };
// The transfer function and its opacity ramp (binding 4).
#define SPECTRAL_TRANSFER_BINDING 4
#include "spectral_transfer.glsl"
// Screen tiles of one band of rows: tiles across, tiles down, tile size in pixels, the
// viewport's corner (x, y), the band's first row and the row after its last, padding; then
// (first, count) per tile of the band into the element lists that follow (tile_bands).
layout(std430, set = 0, binding = 5) readonly buffer Tiles { uint tiles[]; };
layout(location = 0) out vec4 out_colour;

#define SPECTRAL_VOLUME_SAMPLES (8u + 4u * max(SPECTRAL_FIELD_ORDER, SPECTRAL_GEOMETRY_ORDER))
#define SPECTRAL_VOLUME_SUBSTEPS 2u
#define SPECTRAL_VOLUME_SLOTS 16u
// Rounds of SPECTRAL_VOLUME_SLOTS elements a ray may take (the loop's cap: 1,024 elements).
#define SPECTRAL_VOLUME_ROUNDS 64u
// Bisection steps on an element's entry or exit: 2^-20 of a sample interval.
#define SPECTRAL_VOLUME_BISECTIONS 20
// Light left below which a ray stops (well under half of 1/255).
#define SPECTRAL_VOLUME_OPAQUE (1.0 / 4096.0)

vec3 volume_colour(float f) {
    float tc = ramp_coordinate(f, pc.range.x, pc.range.y, pc.flags.y != 0u);
    return texture(colormap, ramp_texcoord(tc, pc.range.z)).rgb;
}

// spectral_pull_hex, and the point lies inside the element.
bool volume_inside(uint e, vec3 x, inout vec3 r) {
    return spectral_pull_hex(e, x, r) && spectral_outside_3d(r) <= pc.misc.y;
}

// Clips [u0, u1] to where g, linear from ga at u = 0 to gb at u = 1, is not positive.
void volume_clip(float ga, float gb, inout float u0, inout float u1) {
    if (ga > 0.0 && gb > 0.0) {
        u1 = -1.0;
    } else if (ga > 0.0) {
        u0 = max(u0, ga / (ga - gb));
    } else if (gb > 0.0) {
        u1 = min(u1, ga / (ga - gb));
    }
}

// The part [u0, u1] of the chord from ra to rb (reference points) inside the reference cube
// or tetrahedron: u0 < u1 when the chord crosses it. Between two samples outside the element,
// a crossing chord says the ray may pass through a corner or edge of it between them.
vec2 volume_chord(vec3 ra, vec3 rb) {
    float u0 = 0.0, u1 = 1.0;
    for (int a = 0; a < 3; ++a) {
        volume_clip(-ra[a], -rb[a], u0, u1);
        if (!SPECTRAL_SIMPLEX) volume_clip(ra[a] - 1.0, rb[a] - 1.0, u0, u1);
    }
    if (SPECTRAL_SIMPLEX) volume_clip(ra.x + ra.y + ra.z - 1.0, rb.x + rb.y + rb.z - 1.0, u0, u1);
    return vec2(u0, u1);
}

// The boundary of element e between t_in (inside, reference point r_in) and t_out (outside),
// bisected: its ray parameter; r_in becomes the reference point of the inside end.
float volume_boundary(uint e, vec3 eye, vec3 d, float t_in, float t_out, inout vec3 r_in) {
    for (int i = 0; i < SPECTRAL_VOLUME_BISECTIONS; ++i) {
        float t = 0.5 * (t_in + t_out);
        vec3 r = r_in;
        if (volume_inside(e, eye + t * d, r)) {
            t_in = t;
            r_in = r;
        } else {
            t_out = t;
        }
    }
    return t_in;
}

// Composites [a, b] (inside element e) onto (C, T) by the midpoint rule in sub-steps, the
// field evaluated at each midpoint (pulled back from r).
void volume_piece(uint e, vec3 eye, vec3 d, float a, float b, inout vec3 r, inout vec3 C, inout float T) {
    float h = (b - a) / float(SPECTRAL_VOLUME_SUBSTEPS);
    for (uint k = 0u; k < SPECTRAL_VOLUME_SUBSTEPS; ++k) {
        float t = a + (float(k) + 0.5) * h;
        spectral_inverse_map_hex(e, eye + t * d, r);
        float f = spectral_value_hex(e, spectral_clamp_3d(r));
        float absorbed = 1.0 - exp(-volume_sigma(f) * h);
        C += T * absorbed * volume_colour(f);
        T *= 1.0 - absorbed;
    }
}

// Composites [a, b] inside element e, the field fa at a and fb at b: split where the field,
// taken linear between them, crosses an opacity point, each piece by volume_piece (one call
// site: lavapipe compiles each inlined copy of the Newton loops anew).
void volume_interval(uint e, vec3 eye, vec3 d, float a, float b, float fa, float fb, inout vec3 r,
                     inout vec3 C, inout float T) {
    if (!(b > a)) return;
    uint n = min(tf_count, uint(SPECTRAL_TRANSFER_POINTS));
    float lo = a;
    bool rising = fb > fa;
    for (uint j = 0u; j <= n; ++j) {
        float hi = b;
        if (j < n) {
            float v = tf_points[rising ? j : n - 1u - j].x;
            if (!((v - fa) * (v - fb) < 0.0)) continue;
            hi = a + (b - a) * (v - fa) / (fb - fa);
        }
        volume_piece(e, eye, d, lo, hi, r, C, T);
        lo = hi;
    }
}

// The lit colour of the sheet of value c at reference point r of element e, seen along d: the
// colour map at c, lit as iso.frag lights its surfaces. Twin of volume_reference's sheet colour.
vec3 volume_sheet_colour(uint e, vec3 r, vec3 d, float c) {
    vec3 rr = spectral_clamp_3d(r);
    mat3 j;
    spectral_map_hex(e, rr, j);
    vec3 n = spectral_level_normal(j, spectral_slot_value_gradient_hex(e, 0u, rr).yzw, d);
    return spectral_ray_lit(volume_colour(c), n, d);
}

// Composites [a, b] inside element e (the field fa at a, reference point ra, and fb at b) with
// its sheets: the root of f − c in [a, b] for each sheet value c with a sign change between
// the ends, bisected, in ray order; the volume between them (volume_interval, skipped in a
// clear medium) and each sheet at its root (one call site: see volume_interval).
void volume_span(uint e, vec3 eye, vec3 d, float a, float b, float fa, float fb, vec3 ra,
                 inout vec3 C, inout float T) {
    uint m = 0u;
    float root_t[SPECTRAL_TRANSFER_SHEETS];
    float root_c[SPECTRAL_TRANSFER_SHEETS];
    vec3 root_r[SPECTRAL_TRANSFER_SHEETS];
    uint sheets = min(tf_sheet_count, uint(SPECTRAL_TRANSFER_SHEETS));
    for (uint k = 0u; k < sheets; ++k) {
        float c = tf_sheets[k];
        if (!((fa - c) * (fb - c) < 0.0)) continue;
        vec3 r = ra;
        float t = spectral_ray_bisect(e, eye, d, a, b, c, fa - c, r);
        // Insertion in ray order.
        uint i = m;
        while (i > 0u && root_t[i - 1u] > t) {
            root_t[i] = root_t[i - 1u];
            root_c[i] = root_c[i - 1u];
            root_r[i] = root_r[i - 1u];
            i -= 1u;
        }
        root_t[i] = t;
        root_c[i] = c;
        root_r[i] = r;
        m += 1u;
    }
    float lo = a, f_lo = fa;
    vec3 r_lo = ra;
    for (uint i = 0u; i <= m; ++i) {
        float hi = i < m ? root_t[i] : b;
        float f_hi = i < m ? root_c[i] : fb;
        if (tf_clear == 0u) volume_interval(e, eye, d, lo, hi, f_lo, f_hi, r_lo, C, T);
        if (i < m) {
            float alpha = clamp(tf_sheet_alpha, 0.0, 1.0);
            C += T * alpha * volume_sheet_colour(e, root_r[i], d, root_c[i]);
            T *= 1.0 - alpha;
            lo = hi;
            f_lo = f_hi;
            r_lo = root_r[i];
        }
    }
}

// Element e's part of the ray within [t0, t1] (its box clipped to its hull): colour C (composited from T = 1),
// transmittance T, and where the ray first enters it; false when it never does.
bool volume_element(uint e, vec3 eye, vec3 d, float t0, float t1, out vec3 C, out float T, out float t_first) {
    C = vec3(0.0);
    T = 1.0;
    t_first = 0.0;
    bool any = false;
    vec3 r = vec3(SPECTRAL_SIMPLEX ? 0.25 : 0.5);
    float step_t = (t1 - t0) / float(SPECTRAL_VOLUME_SAMPLES);
    bool inside_prev = false, pulled_prev = false;
    float t_prev = t0;
    vec3 r_prev = r;
    for (uint s = 0u; s <= SPECTRAL_VOLUME_SAMPLES && T > SPECTRAL_VOLUME_OPAQUE; ++s) {
        float t = t0 + float(s) * step_t;
        bool pulled = spectral_pull_hex(e, eye + t * d, r);
        bool inside = pulled && spectral_outside_3d(r) <= pc.misc.y;
        // Both outside: where the reference chord between them crosses the element, the ray
        // may clip a corner or edge; the ray's point at the chord's middle decides.
        float tm = t;
        vec3 q = r;
        bool chord = false;
        if (!inside && !inside_prev && pulled && pulled_prev) {
            vec2 u = volume_chord(r_prev, r);
            float um = 0.5 * (u.x + u.y);
            q = mix(r_prev, r, um);
            tm = t_prev + um * (t - t_prev);
            chord = u.x < u.y && volume_inside(e, eye + tm * d, q);
        }
        // The element's boundaries between the samples, bisected from an inside point toward
        // an outside one: (inside t, outside t, inside reference point).
        uint bisections = 0u;
        float b_in[2], b_out[2];
        vec3 b_r[2];
        if (inside && !inside_prev && s > 0u) {
            b_in[0] = t; b_out[0] = t_prev; b_r[0] = r; bisections = 1u;
        } else if (!inside && inside_prev) {
            b_in[0] = t_prev; b_out[0] = t; b_r[0] = r_prev; bisections = 1u;
        } else if (chord) {
            b_in[0] = tm; b_out[0] = t_prev; b_r[0] = q;
            b_in[1] = tm; b_out[1] = t; b_r[1] = q;
            bisections = 2u;
        }
        for (uint i = 0u; i < bisections; ++i) {
            b_in[i] = volume_boundary(e, eye, d, b_in[i], b_out[i], b_r[i]);
        }
        // The intervals inside: from (pa, ra) to (pb, rb).
        uint pieces = 0u;
        float pa[2], pb[2];
        vec3 ra[2], rb[2];
        if (inside) {
            pa[0] = inside_prev ? t_prev : (s == 0u ? t : b_in[0]);
            ra[0] = inside_prev ? r_prev : (s == 0u ? r : b_r[0]);
            pb[0] = t; rb[0] = r; pieces = 1u;
        } else if (inside_prev) {
            pa[0] = t_prev; ra[0] = r_prev; pb[0] = b_in[0]; rb[0] = b_r[0]; pieces = 1u;
        } else if (chord) {
            pa[0] = b_in[0]; ra[0] = b_r[0]; pb[0] = tm; rb[0] = q;
            pa[1] = tm; ra[1] = q; pb[1] = b_in[1]; rb[1] = b_r[1];
            pieces = 2u;
        }
        if (pieces > 0u && !any) {
            t_first = pa[0];
            any = true;
        }
        for (uint i = 0u; i < pieces; ++i) {
            float fa = spectral_value_hex(e, spectral_clamp_3d(ra[i]));
            float fb = spectral_value_hex(e, spectral_clamp_3d(rb[i]));
            volume_span(e, eye, d, pa[i], pb[i], fa, fb, ra[i], C, T);
        }
        inside_prev = inside;
        pulled_prev = pulled;
        t_prev = t;
        r_prev = r;
    }
    return any;
}

void main() {
    vec3 eye = pc.pixel_to_world.xyz;
    vec3 d = normalize(far_point.xyz / far_point.w - eye);
    uint tile_size = tiles[2];
    uvec2 pixel = uvec2(gl_FragCoord.xy) - uvec2(tiles[3], tiles[4]);
    uvec2 tile = pixel / tile_size;
    // This band's rows only (a picture whose lists outgrow one buffer is drawn band by band).
    if (tile.x >= tiles[0] || tile.y < tiles[5] || tile.y >= tiles[6]) discard;
    uint at = 8u + 2u * ((tile.y - tiles[5]) * tiles[0] + tile.x);
    uint first = tiles[at], count = tiles[at + 1u];
    vec3 C_total = vec3(0.0);
    float T_total = 1.0;
    bool any = false;
    float t_floor = -1.0;
    float slot_t[SPECTRAL_VOLUME_SLOTS];
    vec4 slot_ct[SPECTRAL_VOLUME_SLOTS];
    for (uint round = 0u; round < SPECTRAL_VOLUME_ROUNDS; ++round) {
        uint n = 0u;
        bool more = false;
        for (uint k = 0u; k < count; ++k) {
            uint e = tiles[first + k];
            vec3 lo = boxes[2u * e].xyz, hi = boxes[2u * e + 1u].xyz;
            vec2 crossing = spectral_ray_hull(e, eye, d, spectral_ray_box(eye, d, lo, hi));
            float t0 = crossing.x, t1 = crossing.y;
            if (!(t0 < t1) || t1 <= t_floor) continue;
            // The ray enters the element no earlier than its hull: past the last slot, later.
            if (n == SPECTRAL_VOLUME_SLOTS && t0 >= slot_t[n - 1u]) {
                more = true;
                continue;
            }
            vec3 C;
            float T, t_first;
            if (!volume_element(e, eye, d, t0, t1, C, T, t_first) || t_first <= t_floor) continue;
            if (n == SPECTRAL_VOLUME_SLOTS) {
                if (t_first >= slot_t[n - 1u]) {
                    more = true;
                    continue;
                }
                more = true;
                n -= 1u;
            }
            // Insertion in order of entry.
            uint i = n;
            while (i > 0u && slot_t[i - 1u] > t_first) {
                slot_t[i] = slot_t[i - 1u];
                slot_ct[i] = slot_ct[i - 1u];
                i -= 1u;
            }
            slot_t[i] = t_first;
            slot_ct[i] = vec4(C, T);
            n += 1u;
        }
        for (uint i = 0u; i < n; ++i) {
            C_total += T_total * slot_ct[i].rgb;
            T_total *= slot_ct[i].a;
        }
        any = any || n > 0u;
        if (!more || n == 0u || T_total < SPECTRAL_VOLUME_OPAQUE) break;
        t_floor = slot_t[n - 1u];
    }
    if (!any) discard;
    if (pc.flags.x != 0u) {
        // Data: the composited colour (over black) and the light left.
        out_colour = vec4(C_total, T_total);
        return;
    }
    vec3 background = vec3(tf_background[0], tf_background[1], tf_background[2]);
    out_colour = vec4(C_total + T_total * background, 1.0);
}
