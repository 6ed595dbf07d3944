// Body of pose_evidence.comp (the tables as texel buffers) and pose_evidence_ssbo.comp
// (storage buffers, past the device's texel-buffer limit); they declare bindings 0, 1, 2,
// 3 and 5 and LOAD_SMP, LOAD_DENSE, LOAD_CELL, LOAD_SPIN, LOAD_FIELD.
// Multi-touch filter: the log score of every pose hypothesis (engine/ops/pose_evidence.cpp
// says what; engine/ops/pose_evidence.h is the CPU mirror, operation for operation).
// The pose arithmetic is `precise` (no fused multiply-adds) so that a pose lands in the
// same grid cell, face and spin as on the CPU reference; only exp/log/atan/sqrt may differ.
//
// Speed on a CPU driver (lavapipe, docs/multitouch.md "Speed"): it runs lanes in SIMD
// with masks, so (1) a storage-buffer read at an offset not known to be uniform is a
// loop over the lanes, one per read whatever its width: the tables are texel fetches
// (gathers) where the device allows, and the storage form reads the cells, dense points
// and spins as vectors (one loop where there were two or six); and (2) the code of
// an `if` runs (masked) even when no lane takes it, so the terms go in segments (below)
// and a term without a field never runs the field's code; (3) one SIMD stream waits on
// each gather in turn, so an invocation runs M hypotheses step by step (main). NS and M
// are specialization constants (h / NS by a constant; M's loops unrolled). Each
// hypothesis's arithmetic and the order of its sum are the mirror's, whatever M.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int NS = 1;  // spins (p.n_spin)
layout(constant_id = 2) const int M = 1;  // hypotheses an invocation runs side by side

// [K, 16] as 4 RGBA32F texels a term: a texel fetch is a branch-free gather on a CPU
// driver, where a storage-buffer read at the loop's offset was a loop over the lanes
// for each of a term's 16 floats (the term's rows took ~10 of the potato's 23 ms).
layout(binding = 4) uniform samplerBuffer Terms;
layout(std430, binding = 6) writeonly buffer Out_ { float outv[]; };    // [H]
layout(push_constant) uniform Push {
    vec3 origin; float inv_voxel;
    int nx; int ny; int nz; int n_spin;
    uint H; uint K; uint F; int own_field;
    float press; float log_floor; float field_floor; float own_weight;
    float exp_floor;  // exp(log_floor), from the host as on the CPU mirror: one exp a term less
} p;

float dot3(vec3 a, vec3 b) { precise float r = (a.x * b.x + a.y * b.y) + a.z * b.z; return r; }
vec3 cross3(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return r;
}
// Row k (0 point, 1 normal, 2 t1) of sample s: one read, not three.
vec3 load_smp(uint s, uint k) { return LOAD_SMP(s * 3u + k).xyz; }

// The grid cell holding q (-1 outside the grid).
int cell_of(vec3 q) {
    precise vec3 u = (q - p.origin) * p.inv_voxel;
    vec3 f = floor(u);
    if (!(f.x >= 0.0 && f.y >= 0.0 && f.z >= 0.0 && f.x < float(p.nx) && f.y < float(p.ny) && f.z < float(p.nz)))
        return -1;
    return (int(f.z) * p.ny + int(f.y)) * p.nx + int(f.x);
}

// The hypothesis nearest a pose with x axis x at sample s (-1: none).
int nearest_hypothesis(int s, vec3 x) {
    if (s < 0) return -1;
    vec3 t1 = load_smp(uint(s), 2u);
    precise vec3 z = load_smp(uint(s), 1u) * -1.0;
    vec3 t2 = cross3(z, t1);
    precise float a = dot3(x, t1), b = dot3(x, t2);
    // The mirror takes the first spin of largest cs.x * a + cs.y * b over all NS. The spins
    // are evenly spaced (2 pi j / NS: the CPU reference checks), so that spin is within one
    // step of atan2(b, a)'s: three candidates, plus spin 0 (the answer when a = b = 0, where
    // atan2 is undefined), with ties to the lowest spin, give the same spin for a ninth of
    // NS = 36's work.
    const float fj = atan(b, a) * (float(NS) / 6.2831853) + 0.5;
    const int j0 = clamp(int(fj - float(NS) * floor(fj / float(NS))), 0, NS - 1);
    const int cand[4] = int[4](0, (j0 + NS - 1) % NS, j0, (j0 + 1) % NS);
    int best = 0;
    float best_v = -3.0;
    for (int c = 0; c < 4; ++c) {
        const int j = cand[c];
        const vec2 cs = LOAD_SPIN(j);
        precise float v = cs.x * a + cs.y * b;
        if (v > best_v || (v == best_v && j < best)) { best_v = v; best = j; }
    }
    return s * NS + best;
}

// Geometry at dense point q (normal n).
float geometry_log(vec3 q, vec3 n, vec3 t, vec3 z, float sd, float sa) {
    precise float e_d = dot3(t - q, n) + p.press;
    // atan2(|z x n|, -z.n), as the CPU mirror: lavapipe's acos is a coarse polynomial.
    vec3 w = cross3(z, n);
    float e_a = atan(sqrt(dot3(w, w)), -dot3(z, n));
    float r = (e_d / sd) * (e_d / sd) + (e_a / sa) * (e_a / sa);
    return log(exp(-0.5 * r) + p.exp_floor);
}

void main() {
    // M hypotheses an invocation, interleaved step by step: each term's reads are a chain of
    // three dependent gathers (cell, the nearest's normal, the pressed point), latency-bound
    // on a CPU driver; M independent chains in one instruction stream overlap their misses.
    // Hypothesis h0 + m * stride for m < M: every h once over all invocations.
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint h0 = gl_GlobalInvocationID.x; h0 < p.H; h0 += stride * uint(M)) {
        uint hm[M];
        precise vec3 z[M], x[M], y[M], t[M];
        float acc[M];
        [[unroll]] for (int m = 0; m < M; ++m) {
            hm[m] = min(h0 + uint(m) * stride, p.H - 1u);  // past H: H - 1 again, not written
            const uint h = hm[m], s = h / uint(NS), j = h % uint(NS);
            z[m] = load_smp(s, 1u) * -1.0;
            const vec3 t1 = load_smp(s, 2u);
            precise vec3 t2 = cross3(z[m], t1);
            const vec2 cs = LOAD_SPIN(j);
            x[m] = t1 * cs.x + t2 * cs.y;
            y[m] = cross3(z[m], x[m]);
            t[m] = load_smp(s, 0u) + z[m] * p.press;
            acc[m] = p.own_field >= 0 ? p.own_weight * LOAD_FIELD(uint(p.own_field) * p.H + h) : 0.0;
        }
        // The terms in order, in segments: the terms up to the next one that reads a field,
        // then that field. A mask-executing driver (lavapipe) runs the code of an `if` even
        // when no lane takes it, so the field's code only runs where a term has one (and
        // once more, masked, when the last term reads none).
        if (p.K > 0u) {
            uint k = 0u;
            do {
                uint kf = k;  // the segment's last term: the next one with a field, or the last
                while (kf + 1u < p.K && int(round(texelFetch(Terms, int(kf * 4u + 3u)).z)) < 0) ++kf;
                vec3 xf[M];
                int sf[M];  // the segment's last term: its x axis and the sample it reads
                [[unroll]] for (int m = 0; m < M; ++m) xf[m] = vec3(0.0), sf[m] = -1;
                do {
                    // Row k: R (row-major, 9), t (3), sigma_d, sigma_a, field, weight.
                    const vec4 r0 = texelFetch(Terms, int(k * 4u)), r1 = texelFetch(Terms, int(k * 4u + 1u));
                    const vec4 r2 = texelFetch(Terms, int(k * 4u + 2u)), r3 = texelFetch(Terms, int(k * 4u + 3u));
                    precise vec3 zk[M], tk[M], xk[M];
                    ivec2 near[M];  // the cell's dense point and its far-face counterpart
                    [[unroll]] for (int m = 0; m < M; ++m) {
                        zk[m] = x[m] * r0.z + y[m] * r1.y + z[m] * r2.x;
                        xk[m] = x[m] * r0.x + y[m] * r0.w + z[m] * r1.z;
                        tk[m] = t[m] + x[m] * r2.y + y[m] * r2.z + z[m] * r2.w;
                        const int cell = cell_of(tk[m]);
                        near[m] = ivec2(-1);
                        if (cell >= 0) near[m] = LOAD_CELL(cell);
                    }
                    // The point the pose presses: the far one where the axis runs along the
                    // nearest's outward normal (pose_evidence.h). Four reads a term: the
                    // cell, that normal, the point (with its sample) and its normal.
                    int i[M];
                    [[unroll]] for (int m = 0; m < M; ++m)
                        i[m] = near[m].x >= 0 && near[m].y >= 0 && dot3(zk[m], LOAD_DENSE(uint(max(near[m].x, 0)) * 2u + 1u).xyz) > 0.0 ? near[m].y : near[m].x;
                    const float sd = r3.x, sa = r3.y;
                    [[unroll]] for (int m = 0; m < M; ++m) {
                        const vec4 q = LOAD_DENSE(uint(max(i[m], 0)) * 2u);
                        const vec3 n = LOAD_DENSE(uint(max(i[m], 0)) * 2u + 1u).xyz;
                        if (sd > 0.0) acc[m] += i[m] < 0 ? p.log_floor : geometry_log(q.xyz, n, tk[m], zk[m], sd, sa);
                        xf[m] = xk[m];
                        sf[m] = i[m] < 0 ? -1 : int(q.w);
                    }
                    ++k;
                } while (k <= kf);
                const vec2 fw = texelFetch(Terms, int(kf * 4u + 3u)).zw;  // field, weight
                const int field = int(round(fw.x));
                if (field >= 0 && uint(field) < p.F) {  // a field past F (refused on the CPU) reads nothing
                    [[unroll]] for (int m = 0; m < M; ++m) {
                        const int hk = nearest_hypothesis(sf[m], xf[m]);
                        acc[m] += fw.y * (hk < 0 ? p.field_floor : LOAD_FIELD(uint(field) * p.H + uint(hk)));
                    }
                }
            } while (k < p.K);
        }
        [[unroll]] for (int m = 0; m < M; ++m)
            if (h0 + uint(m) * stride < p.H) outv[hm[m]] = acc[m];
    }
}
