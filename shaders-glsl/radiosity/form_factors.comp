#version 450
// Form factors at face centroids (seed 000 Eq. 15, constants as in src/radiosity/form_factor.rs)
// for rows row0 .. row0 + rows of F, one invocation per pair (i, j): the facing test, then
// Vis(i, j) by walking the BVH (built on the CPU, src/radiosity/bvh.rs) with the segment
// between the centroids, cast from the lower face index to the higher so that visibility is
// symmetric in f32 too.

layout(local_size_x = 8, local_size_y = 8) in;

layout(constant_id = 0) const uint REGULARISED = 1;

// Per face: centroid and area; unnormalised normal and the sum of squared edge lengths.
layout(std430, set = 0, binding = 0) readonly buffer Faces { vec4 faces[]; };
// Per node: (lo, right_or_first bits), (hi, count bits); depth first.
layout(std430, set = 0, binding = 1) readonly buffer Nodes { vec4 nodes[]; };
// Per triangle in leaf order: three corners; corner 0's w holds the face index's bits.
layout(std430, set = 0, binding = 2) readonly buffer Triangles { vec4 triangles[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Rows { float f[]; };

layout(push_constant) uniform Push {
    uint n;
    uint row0;
    uint rows;
    uint node_count;
} pc;

const float PI = 3.14159265358979;
// Relative threshold of the facing test: f32 rounding of a cosine is ~1e-7.
const float FACING_EPSILON = 1e-5;
// Part of the segment cut off at each end (its end points lie on faces i and j).
const float SEGMENT_MARGIN = 1e-5;
const uint STACK = 48;

bool slab(vec3 lo, vec3 hi, vec3 a, vec3 inv) {
    vec3 t0 = (lo - a) * inv;
    vec3 t1 = (hi - a) * inv;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float near = max(max(tn.x, tn.y), max(tn.z, SEGMENT_MARGIN));
    float far = min(min(tf.x, tf.y), min(tf.z, 1.0 - SEGMENT_MARGIN));
    return !(near > far);
}

// Möller–Trumbore; edges included.
bool crosses(vec3 a, vec3 d, vec3 p0, vec3 p1, vec3 p2) {
    vec3 e1 = p1 - p0;
    vec3 e2 = p2 - p0;
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    if (det == 0.0) {
        return false;
    }
    float inv = 1.0 / det;
    vec3 s = a - p0;
    float u = dot(s, p) * inv;
    if (u < 0.0 || u > 1.0) {
        return false;
    }
    vec3 q = cross(s, e1);
    float v = dot(d, q) * inv;
    if (v < 0.0 || u + v > 1.0) {
        return false;
    }
    float t = dot(e2, q) * inv;
    return t > SEGMENT_MARGIN && t < 1.0 - SEGMENT_MARGIN;
}

bool occluded(vec3 a, vec3 b, uint skip0, uint skip1) {
    vec3 d = b - a;
    vec3 inv = 1.0 / d;
    uint stack[STACK];
    uint top = 1;
    stack[0] = 0;
    while (top > 0) {
        top -= 1;
        uint index = stack[top];
        vec4 lo = nodes[2 * index];
        vec4 hi = nodes[2 * index + 1];
        if (!slab(lo.xyz, hi.xyz, a, inv)) {
            continue;
        }
        uint right_or_first = floatBitsToUint(lo.w);
        uint count = floatBitsToUint(hi.w);
        if (count == 0) {
            stack[top] = right_or_first;
            stack[top + 1] = index + 1;
            top += 2;
        } else {
            for (uint k = right_or_first; k < right_or_first + count; ++k) {
                vec4 p0 = triangles[3 * k];
                uint face = floatBitsToUint(p0.w);
                if (face != skip0 && face != skip1
                    && crosses(a, d, p0.xyz, triangles[3 * k + 1].xyz, triangles[3 * k + 2].xyz)) {
                    return true;
                }
            }
        }
    }
    return false;
}

void main() {
    uint j = gl_GlobalInvocationID.x;
    uint r = gl_GlobalInvocationID.y;
    if (j >= pc.n || r >= pc.rows) {
        return;
    }
    uint i = pc.row0 + r;
    float value = 0.0;
    if (i != j) {
        vec4 ci = faces[2 * i];
        vec4 ni = faces[2 * i + 1];
        vec4 cj = faces[2 * j];
        vec4 nj = faces[2 * j + 1];
        vec3 d = cj.xyz - ci.xyz;
        float sij = dot(ni.xyz, d);
        float sji = -dot(nj.xyz, d);
        float dist = length(d);
        bool facing = sij > FACING_EPSILON * length(ni.xyz) * dist && sji > FACING_EPSILON * length(nj.xyz) * dist;
        if (facing) {
            uint lo = min(i, j);
            uint hi = max(i, j);
            if (!occluded(faces[2 * lo].xyz, faces[2 * hi].xyz, lo, hi)) {
                float rr = dot(d, d);
                if (REGULARISED == 1u) {
                    rr += (ni.w + nj.w) / (16.0 * PI);
                }
                value = sij * sji / (4.0 * PI * rr * rr * ci.w);
            }
        }
    }
    f[r * pc.n + j] = value;
}
