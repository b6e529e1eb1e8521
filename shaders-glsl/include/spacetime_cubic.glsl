// The spacetime DG element field of seed 003 §4.2.1 and its derived fields.
// Twin of src/spacetime/cubic.rs (same monomial order, same formulas); tests/spacetime_fields.rs
// checks they agree.
#ifndef GALERKIN_SPACETIME_CUBIC_GLSL
#define GALERKIN_SPACETIME_CUBIC_GLSL

// Exponents (x, y, t) of 1, x, y, t, x², xy, xt, y², yt, t², x³, x²y, x²t, xy², xyt, xt², y³,
// y²t, yt², t³.
const ivec3 SPACETIME_MONOMIALS[20] = ivec3[20](
    ivec3(0, 0, 0), ivec3(1, 0, 0), ivec3(0, 1, 0), ivec3(0, 0, 1), ivec3(2, 0, 0),
    ivec3(1, 1, 0), ivec3(1, 0, 1), ivec3(0, 2, 0), ivec3(0, 1, 1), ivec3(0, 0, 2),
    ivec3(3, 0, 0), ivec3(2, 1, 0), ivec3(2, 0, 1), ivec3(1, 2, 0), ivec3(1, 1, 1),
    ivec3(1, 0, 2), ivec3(0, 3, 0), ivec3(0, 2, 1), ivec3(0, 1, 2), ivec3(0, 0, 3));

// One element ready for evaluation: frame centre and λ, extents and μ, the 20 displacement
// coefficients (what the slice pipelines pass from the vertex to the fragment stage).
struct SpacetimeElement {
    vec4 centre_lambda;
    vec4 extent_mu;
    vec2 c[20];
};

// One element as stored on the device and in .gst files (std430, 240 bytes): its corners
// (x0 y0 t0 x1)(y1 t1 x2 y2)(t2 x3 y3 t3), frame centre and material index (bits of w),
// extents, the 20 coefficients. Rust: spacetime::ElementRecord.
struct SpacetimeRecord {
    vec4 corners[3];
    vec4 centre_material;
    vec4 extent;
    vec2 c[20];
};

// Corner i (0..3) of a record.
vec3 spacetime_corner(SpacetimeRecord r, uint i) {
    float v[12] = float[12](r.corners[0].x, r.corners[0].y, r.corners[0].z, r.corners[0].w,
                            r.corners[1].x, r.corners[1].y, r.corners[1].z, r.corners[1].w,
                            r.corners[2].x, r.corners[2].y, r.corners[2].z, r.corners[2].w);
    return vec3(v[3u * i], v[3u * i + 1u], v[3u * i + 2u]);
}

// The element of a record with its material (λ, μ, ρ, 0) resolved.
SpacetimeElement spacetime_element(SpacetimeRecord r, vec4 material) {
    SpacetimeElement el;
    el.centre_lambda = vec4(r.centre_material.xyz, material.x);
    el.extent_mu = vec4(r.extent.xyz, material.y);
    el.c = r.c;
    return el;
}

struct SpacetimeFields {
    vec2 displacement;
    vec2 velocity;
    float speed;
    vec2 speed_gradient;
    vec3 strain;   // (ε_xx, ε_yy, ε_xy)
    float strain_energy_density;
};

float spacetime_power(vec4 p, int e) { return e < 0 ? 0.0 : p[e]; }

// The derived fields of §4.2.3 from the displacement u, its spatial derivatives gx = ∂u/∂x and
// gy = ∂u/∂y, the velocity v and its derivatives dvx, dvy (global units), for Lamé λ, μ: strain,
// |v| and its gradient (zero where |v| = 0), U = ½ ε : C ε (plane strain). Shared by the full
// and the slice evaluation; Rust twin: cubic::fields_from_derivatives.
SpacetimeFields spacetime_fields(vec2 u, vec2 gx, vec2 gy, vec2 v, vec2 dvx, vec2 dvy, float lambda, float mu) {
    SpacetimeFields f;
    f.displacement = u;
    f.velocity = v;
    f.strain = vec3(gx.x, gy.y, 0.5 * (gy.x + gx.y));
    f.speed = length(v);
    f.speed_gradient = f.speed > 0.0 ? vec2(dot(v, dvx), dot(v, dvy)) / f.speed : vec2(0.0);
    float tr = f.strain.x + f.strain.y;
    f.strain_energy_density =
        0.5 * (lambda * tr * tr + 2.0 * mu * (f.strain.x * f.strain.x + f.strain.y * f.strain.y
                                                + 2.0 * f.strain.z * f.strain.z));
    return f;
}

// Fields of element `el` at the global spacetime point p = (x, y, t).
SpacetimeFields spacetime_evaluate(SpacetimeElement el, vec3 p) {
    vec3 w = el.extent_mu.xyz;
    vec3 q = (p - el.centre_lambda.xyz) / w;
    vec4 px = vec4(1.0, q.x, q.x * q.x, q.x * q.x * q.x);
    vec4 py = vec4(1.0, q.y, q.y * q.y, q.y * q.y * q.y);
    vec4 pt = vec4(1.0, q.z, q.z * q.z, q.z * q.z * q.z);
    vec2 u = vec2(0.0), ux = vec2(0.0), uy = vec2(0.0), ut = vec2(0.0), utx = vec2(0.0), uty = vec2(0.0);
    for (int k = 0; k < 20; ++k) {
        ivec3 e = SPACETIME_MONOMIALS[k];
        float a = float(e.x), b = float(e.y), d = float(e.z);
        float xa = spacetime_power(px, e.x), yb = spacetime_power(py, e.y), td = spacetime_power(pt, e.z);
        float xa1 = spacetime_power(px, e.x - 1), yb1 = spacetime_power(py, e.y - 1);
        float td1 = spacetime_power(pt, e.z - 1);
        vec2 c = el.c[k];
        u += c * (xa * yb * td);
        ux += c * (a * xa1 * yb * td);
        uy += c * (b * xa * yb1 * td);
        ut += c * (d * xa * yb * td1);
        utx += c * (a * d * xa1 * yb * td1);
        uty += c * (b * d * xa * yb1 * td1);
    }
    // Derivatives in global units: ∂/∂x = (1/w_x) ∂/∂x̂, v = (1/w_t) ∂u/∂t̂.
    return spacetime_fields(u, ux / w.x, uy / w.y, ut / w.z, utx / (w.z * w.x), uty / (w.z * w.y),
                            el.centre_lambda.w, el.extent_mu.w);
}

// An element's cubic restricted to the time plane of a slice: the displacement as a cubic and
// the velocity as a quadratic in local (x, y), so that per-pixel evaluation is 2D. Rust twin:
// spacetime::cubic::SliceCubic (std430, 160 bytes).
struct SpacetimeSliceCubic {
    vec4 frame;      // centre x, y; 1/w_x, 1/w_y
    vec4 material;   // λ, μ, 0, 0
    vec2 a[10];      // u: 1, x, y, x², xy, y², x³, x²y, xy², y³
    vec2 b[6];       // v = ∂u/∂t: 1, x, y, x², xy, y²
};

SpacetimeSliceCubic spacetime_restrict(SpacetimeElement el, float t) {
    SpacetimeSliceCubic s;
    vec3 w = el.extent_mu.xyz;
    s.frame = vec4(el.centre_lambda.xy, 1.0 / w.x, 1.0 / w.y);
    s.material = vec4(el.centre_lambda.w, el.extent_mu.w, 0.0, 0.0);
    float q = (t - el.centre_lambda.z) / w.z, qq = q * q, iw = 1.0 / w.z;
    // SPACETIME_MONOMIALS grouped by their (x, y) part, written out: a loop over the table
    // indexes local arrays by run-time values, which llvmpipe turns into memory traffic.
    s.a[0] = el.c[0] + el.c[3] * q + el.c[9] * qq + el.c[19] * (qq * q);
    s.a[1] = el.c[1] + el.c[6] * q + el.c[15] * qq;
    s.a[2] = el.c[2] + el.c[8] * q + el.c[18] * qq;
    s.a[3] = el.c[4] + el.c[12] * q;
    s.a[4] = el.c[5] + el.c[14] * q;
    s.a[5] = el.c[7] + el.c[17] * q;
    s.a[6] = el.c[10];
    s.a[7] = el.c[11];
    s.a[8] = el.c[13];
    s.a[9] = el.c[16];
    s.b[0] = (el.c[3] + 2.0 * q * el.c[9] + 3.0 * qq * el.c[19]) * iw;
    s.b[1] = (el.c[6] + 2.0 * q * el.c[15]) * iw;
    s.b[2] = (el.c[8] + 2.0 * q * el.c[18]) * iw;
    s.b[3] = el.c[12] * iw;
    s.b[4] = el.c[14] * iw;
    s.b[5] = el.c[17] * iw;
    return s;
}

// The fields of a restricted element at (x, y) on its plane (as spacetime_evaluate there).
SpacetimeFields spacetime_evaluate_slice(SpacetimeSliceCubic s, vec2 p) {
    vec2 q = (p - s.frame.xy) * s.frame.zw;
    float x = q.x, y = q.y, xx = x * x, xy = x * y, yy = y * y;
    vec2 u = s.a[0] + s.a[1] * x + s.a[2] * y + s.a[3] * xx + s.a[4] * xy + s.a[5] * yy
           + s.a[6] * (xx * x) + s.a[7] * (xx * y) + s.a[8] * (x * yy) + s.a[9] * (yy * y);
    vec2 gx = (s.a[1] + 2.0 * s.a[3] * x + s.a[4] * y + 3.0 * s.a[6] * xx + 2.0 * s.a[7] * xy
               + s.a[8] * yy) * s.frame.z;
    vec2 gy = (s.a[2] + s.a[4] * x + 2.0 * s.a[5] * y + s.a[7] * xx + 2.0 * s.a[8] * xy
               + 3.0 * s.a[9] * yy) * s.frame.w;
    vec2 v = s.b[0] + s.b[1] * x + s.b[2] * y + s.b[3] * xx + s.b[4] * xy + s.b[5] * yy;
    vec2 dvx = (s.b[1] + 2.0 * s.b[3] * x + s.b[4] * y) * s.frame.z;
    vec2 dvy = (s.b[2] + s.b[4] * x + 2.0 * s.b[5] * y) * s.frame.w;
    return spacetime_fields(u, gx, gy, v, dvx, dvy, s.material.x, s.material.y);
}

// Unit normal of the height field z = height_scale · |v| (seed 003 §4.2.3); (0, 0, 1) where
// |v| = 0 (the gradient is then zero).
vec3 spacetime_normal(SpacetimeFields f, float height_scale) {
    vec2 g = height_scale * f.speed_gradient;
    return normalize(vec3(-g, 1.0));
}

#endif
