// Body of codebook_score.comp (quads, spins and window minima as texel buffers) and
// codebook_score_ssbo.comp (storage buffers, past the texel limit): they declare bindings
// 0, 1, 3 and LOAD_QUAD, LOAD_SPIN, LOAD_WMIN.
// Render-and-compare: every hypothesis' height map, seen at its spin and pressed to
// the measured press, against the measured indentation, in one pass over the window
// (engine/ops/codebook.cpp says what; engine/ops/codebook_math.h is the CPU mirror,
// operation for operation).
layout(local_size_x_id = 0) in;
// The window's rows and columns when the host fixes them (0: read p.R, p.C): a small window's
// loops then unroll and the measured map's reads have constant offsets.
layout(constant_id = 1) const int KR = 0;
layout(constant_id = 2) const int KC = 0;

layout(std430, binding = 2) readonly buffer Meas_ { float m[]; };      // [R, C]
layout(std430, binding = 4) readonly buffer Press_ { float press_[]; };// [1] the measured press (mm)
layout(std430, binding = 5) writeonly buffer Out_ { float outv[]; };   // [S * NS]
layout(push_constant) uniform Push {
    int H; int NS; int G; int R; int C;
    float inv_cell; float win; float cap; float weight;
    // The fit's basis (codebook_math.h error_basis): inverse squared norms, the squares' means.
    float inv_n; float inv_r; float inv_c; float inv_rr; float inv_cc; float inv_rc; float mr; float mc;
} p;

#include "codebook_window.glsl"

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const float hr = float(p.R - 1) * 0.5, hc = float(p.C - 1) * 0.5;
    const float press = press_[0];
    for (uint h = gl_GlobalInvocationID.x; h < uint(p.H); h += stride) {
        if (!(press > 1e-6)) { outv[h] = 0.0; continue; }
        const uint base = (h / uint(p.NS)) * uint(p.G + 1) * uint(p.G + 1), j = h % uint(p.NS);
        const float cs = LOAD_SPIN(2u * j), sn = LOAD_SPIN(2u * j + 1u);
        precise float top = LOAD_WMIN(h) + press;
        // The error's sums against the basis; its fit then goes by orthogonality.
        precise float s0 = 0.0, sr = 0.0, sc = 0.0, srr = 0.0, scc = 0.0, src = 0.0, s2 = 0.0;
        const int R = KR > 0 ? KR : p.R, C = KC > 0 ? KC : p.C;
        for (int r = 0; r < R; ++r)
            for (int c = 0; c < C; ++c) {
                precise float a = float(r) - hr, b = float(c) - hc;
                precise float e = m[r * C + c] - max(0.0, top - window_depth(base, cs, sn, r, c));
                s0 += e;
                sr += e * a;
                sc += e * b;
                srr += e * (a * a - p.mr);
                scc += e * (b * b - p.mc);
                src += e * (a * b);
                s2 += e * e;
            }
        precise float k0 = s0 * p.inv_n, kr = sr * p.inv_r, kc = sc * p.inv_c, krr = srr * p.inv_rr, kcc = scc * p.inv_cc, krc = src * p.inv_rc;
        precise float err = max(0.0, s2 - (k0 * s0 + kr * sr + kc * sc + krr * srr + kcc * scc + krc * src));
        outv[h] = -p.weight * err / (float(p.R * p.C) * press * press);
    }
}
