#version 450
#extension GL_GOOGLE_include_directive : require
// Render-and-compare: every hypothesis' height map, seen at its spin and pressed to
// the measured depth, against the measured indentation, in one pass over the window
// (engine/ops/codebook.cpp says what; engine/ops/codebook_math.h is the CPU mirror,
// operation for operation).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Quads_ { vec4 quads[]; }; // [S, (G+1)^2] (make_quads)
layout(std430, binding = 1) readonly buffer Spins_ { float spins[]; }; // [NS, 2]
layout(std430, binding = 2) readonly buffer Meas_ { float m[]; };      // [R, C]
layout(std430, binding = 3) readonly buffer Wmin_ { float wmins[]; };  // [S * NS] (codebook_window_min)
layout(std430, binding = 4) writeonly buffer Out_ { float outv[]; };   // [S * NS]
layout(push_constant) uniform Push {
    int H; int NS; int G; int R; int C;
    float inv_cell; float win; float cap; float weight;
    float inv_n; float inv_rr; float inv_cc;  // 1 / (R C), 1 / sum (r - hr)^2, 1 / sum (c - hc)^2 (0: one row/column)
} p;

#include "codebook_window.glsl"

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const float hr = float(p.R - 1) * 0.5, hc = float(p.C - 1) * 0.5;
    const int RC = p.R * p.C;
    float depth = 0.0;
    for (int k = 0; k < RC; ++k) depth = max(depth, m[k]);
    for (uint h = gl_GlobalInvocationID.x; h < uint(p.H); h += stride) {
        if (!(depth > 1e-6)) { outv[h] = 0.0; continue; }
        const uint base = (h / uint(p.NS)) * uint(p.G + 1) * uint(p.G + 1), j = h % uint(p.NS);
        const float cs = spins[2u * j], sn = spins[2u * j + 1u];
        precise float press = wmins[h] + depth;
        // The error's sums; its best plane (tilt and offset) then goes by orthogonality.
        precise float s0 = 0.0, sr = 0.0, sc = 0.0, s2 = 0.0;
        for (int r = 0; r < p.R; ++r)
            for (int c = 0; c < p.C; ++c) {
                precise float e = m[r * p.C + c] - max(0.0, press - window_depth(base, cs, sn, r, c));
                s0 += e;
                sr += e * (float(r) - hr);
                sc += e * (float(c) - hc);
                s2 += e * e;
            }
        precise float k0 = s0 * p.inv_n, kr = sr * p.inv_rr, kc = sc * p.inv_cc;
        precise float err = max(0.0, s2 - (k0 * s0 + kr * sr + kc * sc));
        outv[h] = -p.weight * err / (float(RC) * depth * depth);
    }
}
