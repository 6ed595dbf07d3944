#version 450
// Multi-touch filter: the log score of every pose hypothesis (engine/ops/pose_evidence.cpp
// says what; engine/ops/pose_evidence.h is the CPU mirror, operation for operation).
// The pose arithmetic is `precise` (no fused multiply-adds) so that a pose lands in the
// same grid cell and spin as on the CPU reference; only exp/log/acos may differ.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Samples_ { float smp[]; };  // [S, 9]
layout(std430, binding = 1) readonly buffer Dense_ { float dense[]; };  // [D, 6]
layout(std430, binding = 2) readonly buffer Cells_ { int cells[]; };    // [V, 2]
layout(std430, binding = 3) readonly buffer Spins_ { float spins[]; };  // [NS, 2]
layout(std430, binding = 4) readonly buffer Terms_ { float terms[]; };  // [K, 16]
layout(std430, binding = 5) readonly buffer Fields_ { float fields[]; }; // [F, H]
layout(std430, binding = 6) writeonly buffer Out_ { float outv[]; };    // [H]
layout(push_constant) uniform Push {
    vec3 origin; float inv_voxel;
    int nx; int ny; int nz; int n_spin;
    uint H; uint K; uint F; int own_field;
    float press; float log_floor; float field_floor; float own_weight;
} p;

float dot3(vec3 a, vec3 b) { precise float r = (a.x * b.x + a.y * b.y) + a.z * b.z; return r; }
vec3 cross3(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return r;
}
vec3 load3(uint base, uint which) {  // which 0: samples, 1: dense
    return which == 0u ? vec3(smp[base], smp[base + 1u], smp[base + 2u])
                       : vec3(dense[base], dense[base + 1u], dense[base + 2u]);
}

int cell_of(vec3 q) {
    precise vec3 u = (q - p.origin) * p.inv_voxel;
    vec3 f = floor(u);
    if (!(f.x >= 0.0 && f.y >= 0.0 && f.z >= 0.0 && f.x < float(p.nx) && f.y < float(p.ny) && f.z < float(p.nz)))
        return -1;
    return (int(f.z) * p.ny + int(f.y)) * p.nx + int(f.x);
}

int nearest_hypothesis(int cell, vec3 x) {
    if (cell < 0) return -1;
    int s = cells[2 * cell + 1];
    if (s < 0) return -1;
    vec3 t1 = load3(uint(s) * 9u + 6u, 0u);
    precise vec3 z = load3(uint(s) * 9u + 3u, 0u) * -1.0;
    vec3 t2 = cross3(z, t1);
    precise float a = dot3(x, t1), b = dot3(x, t2);
    int best = 0;
    float best_v = -3.0;
    for (int j = 0; j < p.n_spin; ++j) {
        precise float v = spins[2 * j] * a + spins[2 * j + 1] * b;
        if (v > best_v) { best_v = v; best = j; }
    }
    return s * p.n_spin + best;
}

float geometry_log(int cell, vec3 t, vec3 z, float sd, float sa) {
    int i = cell < 0 ? -1 : cells[2 * cell];
    if (i < 0) return p.log_floor;
    vec3 q = load3(uint(i) * 6u, 1u), n = load3(uint(i) * 6u + 3u, 1u);
    precise float e_d = dot3(t - q, n) + p.press;
    precise float c = -dot3(z, n);
    float e_a = acos(min(1.0, max(-1.0, c)));
    float r = (e_d / sd) * (e_d / sd) + (e_a / sa) * (e_a / sa);
    return log(exp(-0.5 * r) + exp(p.log_floor));
}

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint h = gl_GlobalInvocationID.x; h < p.H; h += stride) {
        const uint s = h / uint(p.n_spin), j = h % uint(p.n_spin);
        precise vec3 z = load3(s * 9u + 3u, 0u) * -1.0;
        vec3 t1 = load3(s * 9u + 6u, 0u);
        precise vec3 t2 = cross3(z, t1);
        precise vec3 x = t1 * spins[2u * j] + t2 * spins[2u * j + 1u];
        precise vec3 y = cross3(z, x);
        precise vec3 t = load3(s * 9u, 0u) + z * p.press;
        float acc = p.own_field >= 0 ? p.own_weight * fields[uint(p.own_field) * p.H + h] : 0.0;
        for (uint k = 0u; k < p.K; ++k) {
            const uint b = k * 16u;
            precise vec3 zk = x * terms[b + 2u] + y * terms[b + 5u] + z * terms[b + 8u];
            precise vec3 xk = x * terms[b] + y * terms[b + 3u] + z * terms[b + 6u];
            precise vec3 tk = t + x * terms[b + 9u] + y * terms[b + 10u] + z * terms[b + 11u];
            const int cell = cell_of(tk);
            const float sd = terms[b + 12u], sa = terms[b + 13u];
            if (sd > 0.0) acc += geometry_log(cell, tk, zk, sd, sa);
            const int field = int(round(terms[b + 14u]));
            if (field >= 0) {
                const int hk = nearest_hypothesis(cell, xk);
                acc += terms[b + 15u] * (hk < 0 ? p.field_floor : fields[uint(field) * p.H + uint(hk)]);
            }
        }
        outv[h] = acc;
    }
}
