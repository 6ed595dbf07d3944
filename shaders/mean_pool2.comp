#version 450
// Each output pixel the mean of its block of up to 2 x 2 input pixels, per channel: [H, W, C] ->
// [ceil(H/2), ceil(W/2), C] (engine/ops/mean_pool2.cpp; CPU mirror gel::mean_pool2 in
// engine/ops/gel_ops.h, in its order: a block's count is a power of two, so the division is exact).
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer X_ { float x[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float y[]; };
layout(push_constant) uniform Push { int H; int W; int C; } p;

float at(int r, int c, int k) { return x[(uint(r) * uint(p.W) + uint(c)) * uint(p.C) + uint(k)]; }

void main() {
    const int h = (p.H + 1) / 2, w = (p.W + 1) / 2;
    const uint n = uint(h) * uint(w) * uint(p.C), lanes = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < n; i += lanes) {
        const int k = int(i % uint(p.C)), q = int(i / uint(p.C)), r = q / w, c = q % w;
        const bool down = 2 * r + 1 < p.H, right = 2 * c + 1 < p.W;
        precise float top = right ? at(2 * r, 2 * c, k) + at(2 * r, 2 * c + 1, k) : at(2 * r, 2 * c, k);
        precise float bottom = !down ? 0.0 : right ? at(2 * r + 1, 2 * c, k) + at(2 * r + 1, 2 * c + 1, k) : at(2 * r + 1, 2 * c, k);
        precise float v = (top + bottom) / float((1 + int(down)) * (1 + int(right)));
        y[i] = v;
    }
}
