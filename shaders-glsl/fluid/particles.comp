#version 450
// Marker particles (seed 000 §6.5), one invocation per particle, the whole frame's substeps
// in one dispatch (particles are independent). Twin of src/fluid/particles.rs
// (advect_particles): the cell velocity rebuilt from the fluxes (Eq. 13) at the frame's end
// geometry, explicit Euler, the geometry moving linearly from g0 to g1 across the substeps, and after each substep the
// capped walk across faces (with the periodic translation across wrap faces), the grid hash
// when the walk is lost, and clamping into the cell at a wall.
// REDUCED (src/fluid/reduced/particles.rs): the state comes from the reduced coordinates, and
// only the vertices and faces of the cells a particle visits are evaluated (§6.5): vertex
// positions as B_g rows times ĝ (moving linearly from ĝ0 to ĝ1), fluxes as B_f rows times f̂.
// Every float array is read as vec4s (src/fluid/gpu.rs packs them): scalar i of a full array is
// component i & 3 of vec4 i >> 2; a B_g or B_f row of m is padded with zeros to M4(m) vec4s, and
// ĝ0, ĝ1, f̂ are each padded the same way, so a row's dot product is M4(m) vec4 dots.
#include "simplex.glsl"

layout(local_size_x = 64) in;

layout(constant_id = 0) const bool REDUCED = false;
// The mesh's dimension, and (reduced) m_g and m_f: constants of the pipeline, so the compiler
// sees every loop's trip count.
layout(constant_id = 1) const uint DIM = 3u;
layout(constant_id = 2) const uint M_G = 0u;
layout(constant_id = 3) const uint M_F = 0u;

// Full: the frame's start geometry g0. Reduced: B_g, d·vertices rows of m_g.
layout(std430, set = 0, binding = 0) readonly buffer G0 { vec4 g0[]; };
// Full: the frame's end geometry g1. Reduced: ĝ0 and ĝ1 (m_g each), then f̂ (m_f).
layout(std430, set = 0, binding = 1) readonly buffer G1 { vec4 g1[]; };
layout(std430, set = 0, binding = 2) readonly buffer Cells { uint cells[]; };
// Per (cell, local face): face index, bit 31 set if the cell's sign σ is −1.
layout(std430, set = 0, binding = 3) readonly buffer Faces { uint face_info[]; };
// Per (cell, local face): neighbour + 1 in bits 0..27 (0: a wall), its local index of the face
// in bits 28..29, bit 30 set for a wrap face.
layout(std430, set = 0, binding = 4) readonly buffer Links { uint links[]; };
// Full: the fluxes. Reduced: B_f, one row of m_f per face, rows below `reduced.z` here…
layout(std430, set = 0, binding = 5) readonly buffer Flux { vec4 flux[]; };
// xyz position, w the cell's bits.
layout(std430, set = 0, binding = 6) buffer Particles { vec4 particles[]; };
layout(std430, set = 0, binding = 7) readonly buffer GridStart { uint grid_start[]; };
layout(std430, set = 0, binding = 8) readonly buffer GridCells { uint grid_cells[]; };
// walked, hashed, clamped.
layout(std430, set = 0, binding = 9) buffer Counts { uint counts[]; };
// …and the rest here (B_f may exceed one storage binding). Full: unused.
layout(std430, set = 0, binding = 10) readonly buffer FluxHigh { vec4 flux_high[]; };
// Each particle's speed at the end of the frame (its cell's, Eq. 13), for colouring sprites.
layout(std430, set = 0, binding = 11) writeonly buffer Speeds { float particle_speed[]; };

layout(push_constant) uniform Push {
    uint count;
    uint substeps;
    float frame_time;
    uint split;       // reduced: the first face of FluxHigh
    vec4 grid_lo;     // xyz
    vec4 grid_size;   // xyz
    uvec4 grid_dims;  // xyz
} pc;

const uint WALK_CAP = 64u;

// The vec4s a row of m floats occupies.
uint M4(uint m) {
    return (m + 3u) >> 2;
}
const float INSIDE = -1e-6;  // f32: a few ulps of a barycentric weight

// Vertex v at the frame's start (a) and end (b); at fraction t it is a + t (b − a).
void vertex_ends(uint v, out vec3 a, out vec3 b) {
    a = vec3(0.0);
    b = vec3(0.0);
    if (REDUCED) {
        uint m4 = M4(M_G);
        for (uint k = 0u; k < DIM; ++k) {
            uint row = (DIM * v + k) * m4;
            for (uint j = 0u; j < m4; ++j) {
                vec4 r = g0[row + j];
                a[k] += dot(r, g1[j]);
                b[k] += dot(r, g1[m4 + j]);
            }
        }
    } else {
        for (uint k = 0u; k < DIM; ++k) {
            uint i = DIM * v + k;
            a[k] = g0[i >> 2][i & 3u];
            b[k] = g1[i >> 2][i & 3u];
        }
    }
}

float face_flux(uint face) {
    if (!REDUCED) {
        return flux[face >> 2][face & 3u];
    }
    uint m4 = M4(M_F);
    uint coefficients = 2u * M4(M_G);
    float s = 0.0;
    // Two loops, not one choosing its binding per load: a select would load from both.
    if (face < pc.split) {
        for (uint j = 0u; j < m4; ++j) s += dot(flux[face * m4 + j], g1[coefficients + j]);
    } else {
        uint row = (face - pc.split) * m4;
        for (uint j = 0u; j < m4; ++j) s += dot(flux_high[row + j], g1[coefficients + j]);
    }
    return s;
}

// Cell c's corners at the frame's start and end (CellCorners in src/fluid/particles.rs): a
// particle keeps its cell's while it stays there, so a substep evaluates no vertex (no B_g
// row) unless the particle changes cell.
void cell_corners(uint c, out vec3 p0[4], out vec3 p1[4]) {
    p0[3] = vec3(0.0);
    p1[3] = vec3(0.0);
    for (uint i = 0u; i <= DIM; ++i) {
        vertex_ends(cells[(DIM + 1u) * c + i], p0[i], p1[i]);
    }
}

void corners_at(vec3 p0[4], vec3 p1[4], float t, out vec3 p[4]) {
    for (uint i = 0u; i < 4u; ++i) {
        p[i] = p0[i] + t * (p1[i] - p0[i]);
    }
}

// The fluxes σ f out of cell c through its local faces 0…DIM, evaluated by this invocation.
vec4 cell_fluxes(uint c) {
    vec4 out_f = vec4(0.0);
    for (uint l = 0u; l <= DIM; ++l) {
        uint info = face_info[(DIM + 1u) * c + l];
        float sigma = (info & 0x80000000u) != 0u ? -1.0 : 1.0;
        out_f[l] = sigma * face_flux(info & 0x7fffffffu);
    }
    return out_f;
}



// Eq. 13: u_c = V⁻¹ Σ_faces σ f (x_face − x_c), with the cell's corners p and its faces' σ f.
vec3 cell_velocity(vec3 p[4], vec4 fluxes) {
    float vol = simplex_volume(DIM, p);
    vec3 xc = simplex_centroid(DIM, p);
    vec3 u = vec3(0.0);
    for (uint l = 0u; l <= DIM; ++l) {
        u += fluxes[l] * (simplex_face_centroid(DIM, p, l) - xc);
    }
    return u / vol;
}

// Barycentric-clipped closest point of the cell.
vec3 clamp_into(vec3 p[4], vec3 x) {
    vec4 b = simplex_barycentrics(DIM, p, x);
    float w[4];
    float s = 0.0;
    for (uint k = 0u; k <= DIM; ++k) {
        w[k] = max(b[k], 0.0);
        s += w[k];
    }
    if (s <= 0.0) {
        return simplex_centroid(DIM, p);
    }
    vec3 out_p = vec3(0.0);
    for (uint k = 0u; k <= DIM; ++k) {
        out_p += (w[k] / s) * p[k];
    }
    return out_p;
}

bool inside(vec3 p[4], vec3 x) {
    vec4 b = simplex_barycentrics(DIM, p, x);
    for (uint k = 0u; k <= DIM; ++k) {
        if (b[k] < INSIDE) {
            return false;
        }
    }
    return true;
}

// 0 walked, 1 hashed, 2 clamped. p0, p1: the corners of cell c on entry and of the cell found
// on return.
uint locate(inout vec3 x, inout uint c, float t, inout vec3 p0[4], inout vec3 p1[4]) {
    for (uint step = 0u; step < WALK_CAP; ++step) {
        vec3 p[4];
        corners_at(p0, p1, t, p);
        vec4 b = simplex_barycentrics(DIM, p, x);
        uint worst_k = 0u;
        float worst = 1e30;
        for (uint k = 0u; k <= DIM; ++k) {
            if (b[k] < worst) {
                worst = b[k];
                worst_k = k;
            }
        }
        if (worst >= INSIDE) {
            return 0u;
        }
        uint link = links[(DIM + 1u) * c + worst_k];
        uint e1 = link & 0x0fffffffu;
        if (e1 == 0u) {
            x = clamp_into(p, x);
            return 2u;
        }
        uint e = e1 - 1u;
        cell_corners(e, p0, p1);
        if ((link & 0x40000000u) != 0u) {
            vec3 q[4];
            corners_at(p0, p1, t, q);
            uint theirs = (link >> 28) & 3u;
            x += simplex_face_centroid(DIM, q, theirs) - simplex_face_centroid(DIM, p, worst_k);
        }
        c = e;
    }
    uvec3 cell_index = uvec3(0u);
    for (uint k = 0u; k < 3u; ++k) {
        float s = floor((x[k] - pc.grid_lo[k]) / pc.grid_size[k]);
        cell_index[k] = uint(clamp(s, 0.0, float(pc.grid_dims[k] - 1u)));
    }
    uint bucket = (cell_index.z * pc.grid_dims.y + cell_index.y) * pc.grid_dims.x + cell_index.x;
    for (uint i = grid_start[bucket]; i < grid_start[bucket + 1u]; ++i) {
        uint cand = grid_cells[i];
        vec3 q0[4];
        vec3 q1[4];
        vec3 q[4];
        cell_corners(cand, q0, q1);
        corners_at(q0, q1, t, q);
        if (inside(q, x)) {
            c = cand;
            p0 = q0;
            p1 = q1;
            return 1u;
        }
    }
    vec3 p[4];
    corners_at(p0, p1, t, p);
    x = clamp_into(p, x);
    return 2u;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count) {
        return;
    }
    vec3 x = particles[i].xyz;
    uint c = floatBitsToUint(particles[i].w);
    float dt = pc.frame_time / float(pc.substeps);
    uint tally[3] = uint[3](0u, 0u, 0u);
    // The particle's cell's corners, kept while it stays there, and the velocity of the frame's
    // end state in that cell: evaluated again only when the particle changed cell (the flux
    // rows cost m_f per face on the reduced state).
    vec3 p0[4];
    vec3 p1[4];
    cell_corners(c, p0, p1);
    uint velocity_cell = 0xffffffffu;
    vec3 velocity = vec3(0.0);
    for (uint s = 0u; s < pc.substeps; ++s) {
        if (c != velocity_cell) {
            velocity = cell_velocity(p1, cell_fluxes(c));
            velocity_cell = c;
        }
        x += dt * velocity;
        float t1 = float(s + 1u) / float(pc.substeps);
        tally[locate(x, c, t1, p0, p1)] += 1u;
    }
    particles[i] = vec4(x, uintBitsToFloat(c));
    particle_speed[i] = length(c == velocity_cell ? velocity : cell_velocity(p1, cell_fluxes(c)));
    for (uint k = 0u; k < 3u; ++k) {
        if (tally[k] != 0u) {
            atomicAdd(counts[k], tally[k]);
        }
    }
}
