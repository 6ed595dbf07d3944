#version 450
// A coarse solve's answer zc [h, w] as the start of the solve on the grid it halved [H, W]:
// bilinear between the coarse pixels' centres (clamped), times 2, 0 where mask <= 0.5
// (engine/ops/poisson_prolong.cpp; CPU mirror gel::poisson_prolong in engine/ops/gel_ops.h,
// operation for operation).
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer Zc_ { float zc[]; };
layout(std430, binding = 1) readonly buffer Mask_ { float mask[]; };
layout(std430, binding = 2) writeonly buffer Z_ { float z0[]; };
layout(push_constant) uniform Push { int H; int W; int h; int w; } p;

float zat(int r, int c) { return zc[uint(r) * uint(p.w) + uint(c)]; }

void main() {
    const uint n = uint(p.H) * uint(p.W), lanes = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint q = gl_GlobalInvocationID.x; q < n; q += lanes) {
        if (!(mask[q] > 0.5)) {
            z0[q] = 0.0;
            continue;
        }
        const int r = int(q / uint(p.W)), c = int(q % uint(p.W));
        precise float fy = clamp(0.5 * float(r) - 0.25, 0.0, float(p.h - 1));
        precise float fx = clamp(0.5 * float(c) - 0.25, 0.0, float(p.w - 1));
        const int a = p.h > 1 ? min(int(fy), p.h - 2) : 0, b = p.w > 1 ? min(int(fx), p.w - 2) : 0;
        const int a1 = min(a + 1, p.h - 1), b1 = min(b + 1, p.w - 1);
        precise float wy = fy - float(a), wx = fx - float(b);
        precise float top = (1.0 - wx) * zat(a, b) + wx * zat(a, b1);
        precise float bottom = (1.0 - wx) * zat(a1, b) + wx * zat(a1, b1);
        precise float v = 2.0 * ((1.0 - wy) * top + wy * bottom);
        z0[q] = v;
    }
}
