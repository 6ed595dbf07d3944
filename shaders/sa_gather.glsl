// Body of sa_gather.comp (U and W read as texel buffers) and sa_gather_ssbo.comp
// (beyond the texel-buffer limit); they declare bindings 0 and 3 and LOAD_U, LOAD_W.
// Layer one of a set-abstraction MLP from its per-point part (engine/ops/sa_gather.cpp):
// y[n][m] = act(U[n][q] - W[K-3..K-1][n] . centre[s]), row m = (s, j), q = idx[m].
// One invocation per row (4 rows where M % 4 == 0: a CPU driver stores lane by
// lane, a branch each, so one vec4 store instead of 4) through every channel: the
// rows' indices and centres are read once, the weights are the same for every
// invocation (the loops' trip counts are uniform: spare invocations redo the last
// rows and store nothing).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool ROW4 = true;  // M % 4 == 0: 4 rows per invocation, stored as one vec4
#include "act.glsl"

layout(std430, binding = 1) readonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 2) readonly buffer Index_ { int idx[]; };     // [S, NS]
layout(std430, binding = 4) writeonly buffer Y_ { vec4 Y[]; };         // [N, M]
layout(push_constant) uniform Push { uint M; uint NS; uint P; uint K; uint N; uint act; float slope; } p;

const uint R = ROW4 ? 4u : 1u;

void main() {
    const uint units = p.M / R;
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const uint passes = (units + stride - 1u) / stride;
    for (uint i = 0u; i < passes; ++i) {
        const uint u_all = gl_GlobalInvocationID.x + i * stride;
        const uint m0 = min(u_all, units - 1u) * R;
        uint q[4];
        vec3 c[4];
        for (uint r = 0u; r < R; ++r) {
            q[r] = min(uint(idx[m0 + r]), p.P - 1u);  // in range whatever the indices hold
            const uint s = 3u * ((m0 + r) / p.NS);
            c[r] = vec3(centre[s], centre[s + 1u], centre[s + 2u]);
        }
        for (uint n = 0u; n < p.N; ++n) {
            const vec3 wx = vec3(LOAD_W((p.K - 3u) * p.N + n), LOAD_W((p.K - 2u) * p.N + n), LOAD_W((p.K - 1u) * p.N + n));
            vec4 v;
            for (uint r = 0u; r < R; ++r)
                v[r] = apply_act(LOAD_U(n * p.P + q[r]) - (wx.x * c[r].x + wx.y * c[r].y + wx.z * c[r].z), p.act, p.slope);
            const uint e = n * p.M + m0;
            if (u_all < units) {
                if (ROW4) Y[e / 4u] = v;
                else Y[e / 4u][e % 4u] = v.x;
            }
        }
    }
}
