// main of ilu.comp and ilu_subgroup.comp: the whole ILU (SPEC 2) in one dispatch,
// one workgroup per touch: all N iterations (N read from a buffer, so it can
// change between runs without re-recording).
#include "ilu_core.glsl"

layout(std430, binding = 13) writeonly buffer Cs_ { float cs[]; };      // [B, Nmax, 3]
layout(std430, binding = 14) writeonly buffer Contact_ { float contact[]; };  // [B, 3]
layout(push_constant) uniform Push { uint max_iters; } p;

void main() {
    ilu_init();
    const uint n = uint(clamp(iters, 0, int(p.max_iters)));
    const uint cs0 = gl_WorkGroupID.x * p.max_iters * 3u;
    for (uint it = 0u; it < n; ++it) {
        ilu_iteration();
        if (tid < 3u) cs[cs0 + it * 3u + tid] = c[tid];
    }
    for (uint i = n * 3u + tid; i < p.max_iters * 3u; i += L) cs[cs0 + i] = 0.0;
    if (tid < 3u) contact[gl_WorkGroupID.x * 3u + tid] = c[tid];
}
