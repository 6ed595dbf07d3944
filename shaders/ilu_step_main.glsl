// main of ilu_step.comp and ilu_step_subgroup.comp.
// One ILU iteration per dispatch, the state carried in a buffer between
// dispatches: the bench's diagnostic recording, with a timestamp between
// iterations. Step 0 starts from F^t (its state input is not read).
// State: [h (C) | gx (3C) | c (3) | c_1..c_Nmax (3 Nmax)].
#include "ilu_core.glsl"

layout(std430, binding = 13) readonly buffer In_ { float sin_[]; };
layout(std430, binding = 14) writeonly buffer Out_ { float sout[]; };
layout(std430, binding = 15) writeonly buffer Cs_ { float cs[]; };      // [Nmax, 3]
layout(std430, binding = 16) writeonly buffer Contact_ { float contact[]; };  // [3]
layout(push_constant) uniform Push { uint max_iters; uint step; } p;

void main() {
    const uint rows = 3u * p.max_iters, at = 4u * C + 3u;  // c_1..c_Nmax start at `at`
    if (p.step == 0u) {
        ilu_init();
    } else {
        ilu_load_x();
        for (uint i = tid; i < C; i += L) h[i] = sin_[i];
        for (uint i = tid; i < C3; i += L) gx[i] = sin_[C + i];
        if (tid < 3u) c[tid] = sin_[4u * C + tid];
        barrier();
    }
    const uint n = uint(clamp(iters, 0, int(p.max_iters)));
    if (p.step < n) ilu_iteration();
    // Rows before this step come from the input state (zeros at step 0).
    for (uint i = tid; i < rows; i += L) {
        float v = (i / 3u == p.step) ? (p.step < n ? c[i % 3u] : 0.0) : (i / 3u < p.step ? sin_[at + i] : 0.0);
        sout[at + i] = v;
        cs[i] = v;
    }
    for (uint i = tid; i < C; i += L) sout[i] = h[i];
    for (uint i = tid; i < C3; i += L) sout[C + i] = gx[i];
    if (tid < 3u) {
        sout[4u * C + tid] = c[tid];
        contact[tid] = c[tid];
    }
}
