#version 450
// Peak-throughput probe: 8 independent vec4 fma chains per invocation, so the
// measured rate is the device's arithmetic limit, not latency or memory.
// FLOPs per invocation = ITERS * 8 chains * 4 lanes * 2.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint ITERS = 256;

layout(std430, binding = 0) writeonly buffer Out_ { vec4 outv[]; };
layout(push_constant) uniform Push { float seed; } p;

void main() {
    vec4 m = vec4(0.999, 1.001, 0.998, 1.002);
    vec4 c = vec4(1e-3, -1e-3, 2e-3, -2e-3);
    vec4 a0 = vec4(p.seed + float(gl_GlobalInvocationID.x)), a1 = a0 + 1.0, a2 = a0 + 2.0, a3 = a0 + 3.0;
    vec4 a4 = a0 + 4.0, a5 = a0 + 5.0, a6 = a0 + 6.0, a7 = a0 + 7.0;
    for (uint i = 0; i < ITERS; ++i) {
        a0 = fma(a0, m, c); a1 = fma(a1, m, c); a2 = fma(a2, m, c); a3 = fma(a3, m, c);
        a4 = fma(a4, m, c); a5 = fma(a5, m, c); a6 = fma(a6, m, c); a7 = fma(a7, m, c);
    }
    // One store per invocation keeps the chains alive without costing bandwidth.
    outv[gl_GlobalInvocationID.x] = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
}
