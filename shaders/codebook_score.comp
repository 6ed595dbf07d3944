#version 450
// Render-and-compare: every hypothesis' height map, seen at its spin and pressed to
// the measured depth, against the measured indentation (engine/ops/codebook.cpp says
// what; engine/ops/codebook_math.h is the CPU mirror, operation for operation).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const int RC_MAX = 1;  // R * C: the window's depths are seen once and kept

layout(std430, binding = 0) readonly buffer Book_ { float book[]; };   // [S, G*G]
layout(std430, binding = 1) readonly buffer Spins_ { float spins[]; }; // [NS, 2]
layout(std430, binding = 2) readonly buffer Meas_ { float m[]; };      // [R, C]
layout(std430, binding = 3) writeonly buffer Out_ { float outv[]; };   // [S * NS]
layout(push_constant) uniform Push {
    int H; int NS; int G; int R; int C;
    float inv_cell; float win; float cap; float weight;
    float inv_n; float inv_rr; float inv_cc;  // 1 / (R C), 1 / sum (r - hr)^2, 1 / sum (c - hc)^2 (0: one row/column)
} p;

float at(uint base, int i, int j) { return i < 0 || j < 0 || i >= p.G || j >= p.G ? p.cap : book[base + uint(j * p.G + i)]; }

float book_at(uint base, float fa, float fb) {
    const float a0 = floor(fa), b0 = floor(fb);
    precise float wa = fa - a0, wb = fb - b0;
    const int i = int(a0), j = int(b0);
    precise float top = at(base, i, j) * (1.0 - wa) + at(base, i + 1, j) * wa;
    precise float bot = at(base, i, j + 1) * (1.0 - wa) + at(base, i + 1, j + 1) * wa;
    precise float r = top * (1.0 - wb) + bot * wb;
    return r;
}

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const float hr = float(p.R - 1) * 0.5, hc = float(p.C - 1) * 0.5, half_ = float(p.G - 1) * 0.5;
    const int RC = p.R * p.C;
    float depth = 0.0;
    for (int k = 0; k < RC; ++k) depth = max(depth, m[k]);
    for (uint h = gl_GlobalInvocationID.x; h < uint(p.H); h += stride) {
        if (!(depth > 1e-6)) { outv[h] = 0.0; continue; }
        const uint base = (h / uint(p.NS)) * uint(p.G) * uint(p.G), j = h % uint(p.NS);
        const float cs = spins[2u * j], sn = spins[2u * j + 1u];
        float seen[RC_MAX];
        float wmin = p.cap;
        for (int r = 0; r < p.R; ++r)
            for (int c = 0; c < p.C; ++c) {
                precise float u = (float(c) - hc) * p.win, v = (float(r) - hr) * p.win;
                precise float a = u * cs - v * sn, b = u * sn + v * cs;
                precise float fa = a * p.inv_cell + half_, fb = b * p.inv_cell + half_;
                const float w = book_at(base, fa, fb);
                seen[r * p.C + c] = w;
                wmin = min(wmin, w);
            }
        // The error's best plane (tilt and offset) goes: its coefficients, then the rest.
        precise float s0 = 0.0, sr = 0.0, sc = 0.0;
        for (int r = 0; r < p.R; ++r)
            for (int c = 0; c < p.C; ++c) {
                precise float e = m[r * p.C + c] - max(0.0, wmin + depth - seen[r * p.C + c]);
                s0 += e;
                sr += e * (float(r) - hr);
                sc += e * (float(c) - hc);
            }
        precise float k0 = s0 * p.inv_n, kr = sr * p.inv_rr, kc = sc * p.inv_cc;
        precise float err = 0.0;
        for (int r = 0; r < p.R; ++r)
            for (int c = 0; c < p.C; ++c) {
                precise float e = m[r * p.C + c] - max(0.0, wmin + depth - seen[r * p.C + c]);
                precise float f = e - (k0 + kr * (float(r) - hr) + kc * (float(c) - hc));
                err += f * f;
            }
        outv[h] = -p.weight * err / (float(RC) * depth * depth);
    }
}
