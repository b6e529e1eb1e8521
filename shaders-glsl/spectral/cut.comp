#version 450
// Cut planes through hexahedral spectral elements (the seed's future work, across many
// elements): for each element and plane n · x = d, the element is crossed when the plane
// separates its Bernstein control points (their convex hull contains the element); then the
// rectangle that bounds the control points projected onto the plane is appended to the draw —
// it contains the element's whole section, which the fragment stage (cut.frag) cuts out
// exactly by Newton's method in (xi, eta, zeta).

layout(local_size_x = 64) in;
// Planes (unit normal, d).
layout(std430, set = 0, binding = 3) readonly buffer Planes { vec4 planes[]; };
// Bernstein control points of each element's geometry, (g + 1)^3 per element.
layout(std430, set = 0, binding = 4) readonly buffer Hull { vec4 hull[]; };
layout(std430, set = 0, binding = 5) buffer Draw { uint vertex_count; uint instances; uint first_vertex; uint first_instance; } draw;
struct DrawVertex { float x, y, z, plane, unused; uint element; };
layout(std430, set = 0, binding = 6) writeonly buffer Vertices { DrawVertex vertices[]; };
layout(push_constant) uniform CutPush { uint elements; uint points_per_element; } pc;

void main() {
    uint e = gl_GlobalInvocationID.x;
    uint k = gl_WorkGroupID.y;
    if (e >= pc.elements) return;
    vec3 n = planes[k].xyz;
    float d = planes[k].w;
    // A basis (u, v) of the plane.
    vec3 u = normalize(abs(n.x) < 0.9 ? cross(n, vec3(1.0, 0.0, 0.0)) : cross(n, vec3(0.0, 1.0, 0.0)));
    vec3 v = cross(n, u);
    float lo = 1e30, hi = -1e30;
    vec2 rmin = vec2(1e30), rmax = vec2(-1e30);
    float size = 0.0;
    for (uint q = 0u; q < pc.points_per_element; ++q) {
        vec3 p = hull[e * pc.points_per_element + q].xyz;
        float s = dot(n, p) - d;
        lo = min(lo, s);
        hi = max(hi, s);
        vec2 uv = vec2(dot(u, p), dot(v, p));
        rmin = min(rmin, uv);
        rmax = max(rmax, uv);
        size = max(size, max(abs(p.x), max(abs(p.y), abs(p.z))));
    }
    // Crossed within f32 rounding of the control points (a few ulps of the coordinates): a
    // plane lying on a face between two elements meets the face's control points only to
    // rounding, and without this slack it could miss the elements on both sides.
    float slack = 8.0 * 1.2e-7 * size;
    if (lo > slack || hi < -slack) return;
    // Grown by the same rounding at the corners.
    vec2 grow = vec2(slack);
    rmin -= grow;
    rmax += grow;
    vec3 o = d * n;
    vec3 c00 = o + rmin.x * u + rmin.y * v, c10 = o + rmax.x * u + rmin.y * v;
    vec3 c11 = o + rmax.x * u + rmax.y * v, c01 = o + rmin.x * u + rmax.y * v;
    uint at = atomicAdd(draw.vertex_count, 6u);
    vec3 corners[6] = vec3[6](c00, c10, c11, c00, c11, c01);
    for (uint i = 0u; i < 6u; ++i) {
        vertices[at + i] = DrawVertex(corners[i].x, corners[i].y, corners[i].z, float(k), 0.0, e);
    }
}
