#version 450
// A log field over the hypotheses (sample s, spin j) widened by odometry slack:
// out[f, s NS + j] = the best of in[f] at (s, j), at the spins j +- 1 less a_r step^2,
// and at each neighbour s' of s (at the spin j + off that keeps the pose's heading)
// less a_t d^2 (engine/ops/field_slack.cpp; a_t, a_r = 0: that slack is off).
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer In_ { float fin[]; };       // [F, S * NS]
layout(std430, binding = 1) readonly buffer Nb_ { float nb[]; };        // [S, KN, 3]: s' (-1: none), d^2, off
layout(std430, binding = 2) readonly buffer Wd_ { float width[]; };     // [F, 2]: a_t, a_r
layout(std430, binding = 3) writeonly buffer Out_ { float fout[]; };
layout(push_constant) uniform Push { uint F; uint S; uint NS; uint KN; float step2; } p;

// Below the smallest normal float: 0, as the CPU reference takes it (a device may flush subnormals).
const float kMinNormal = 1.17549435e-38;
float normal_or_zero(float x) { return x >= kMinNormal ? x : 0.0; }

void main() {
    const uint H = p.S * p.NS, total = p.F * H, stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint e = gl_GlobalInvocationID.x; e < total; e += stride) {
        const uint f = e / H, h = e - f * H, s = h / p.NS, j = h - s * p.NS, base = f * H;
        const float at = normal_or_zero(width[2u * f]), ar = normal_or_zero(width[2u * f + 1u]);
        float v = fin[e];
        if (ar > 0.0 && p.NS > 1u) {
            precise float pen = ar * p.step2;
            v = max(v, fin[base + s * p.NS + (j + 1u) % p.NS] - pen);
            v = max(v, fin[base + s * p.NS + (j + p.NS - 1u) % p.NS] - pen);
        }
        if (at > 0.0) {
            for (uint k = 0u; k < p.KN; ++k) {
                const uint r = (s * p.KN + k) * 3u;
                const float idx = nb[r], d2 = nb[r + 1u], off = nb[r + 2u];
                // A row's neighbours come first, then -1s; an entry out of range (a user's table) ends it too.
                if (!(idx >= 0.0 && idx < 4294967296.0 && uint(idx) < p.S && off >= 0.0 && off < float(p.NS) && d2 >= 0.0)) break;
                precise float pen = d2 >= kMinNormal ? at * d2 : 0.0;  // at = inf, d^2 = 0 would be NaN
                // Clamped too: a driver may assume no NaN (no SignedZeroInfNanPreserve) and pass one above.
                const uint s2 = min(uint(idx), p.S - 1u), o2 = min(uint(off), p.NS - 1u);
                v = max(v, fin[base + s2 * p.NS + (j + o2) % p.NS] - pen);
            }
        }
        fout[e] = v;
    }
}
