// Body of sa_gather.comp (U read as a texel buffer) and sa_gather_ssbo.comp (U
// beyond the texel-buffer limit); they declare binding 0 and LOAD_U.
// Layer one of a set-abstraction MLP from its per-point part (engine/ops/sa_gather.cpp):
// y[n][m] = act(U[n][q] - W[K-3..K-1][n] . centre[s]), row m = (s, j), q = idx[m].
// One invocation per row through every channel: the row's index and centre are
// read once, the weights are the same for every invocation (the loops' trip
// counts are uniform: spare invocations redo the last row and store nothing).
layout(local_size_x_id = 0) in;
#include "act.glsl"

layout(std430, binding = 1) readonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 2) readonly buffer Index_ { int idx[]; };     // [S, NS]
layout(std430, binding = 3) readonly buffer W_ { float W[]; };         // [K, N]
layout(std430, binding = 4) writeonly buffer Y_ { float Y[]; };        // [N, M]
layout(push_constant) uniform Push { uint M; uint NS; uint P; uint K; uint N; uint act; float slope; } p;

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const uint passes = (p.M + stride - 1u) / stride;
    for (uint i = 0u; i < passes; ++i) {
        const uint m_all = gl_GlobalInvocationID.x + i * stride;
        const uint m = min(m_all, p.M - 1u);
        const uint q = min(uint(idx[m]), p.P - 1u);  // in range whatever the indices hold
        const uint s = 3u * (m / p.NS);
        const vec3 c = vec3(centre[s], centre[s + 1u], centre[s + 2u]);
        for (uint n = 0u; n < p.N; ++n) {
            const vec3 wx = vec3(W[(p.K - 3u) * p.N + n], W[(p.K - 2u) * p.N + n], W[(p.K - 1u) * p.N + n]);
            const float v = apply_act(LOAD_U(n * p.P + q) - (wx.x * c.x + wx.y * c.y + wx.z * c.z), p.act, p.slope);
            if (m_all < p.M) Y[n * p.M + m] = v;
        }
    }
}
