#version 450
#extension GL_GOOGLE_include_directive : require
// The shallowest depth of each hypothesis' map under the comparison window (the
// depth its press is measured from): per window size, once, not per touch
// (engine/ops/codebook.cpp; engine/ops/codebook_math.h window_min is the CPU mirror).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Quads_ { vec4 quads[]; }; // [S, (G+1)^2] (make_quads)
#define LOAD_QUAD(i) quads[i]
layout(std430, binding = 1) readonly buffer Spins_ { float spins[]; }; // [NS, 2]
layout(std430, binding = 2) writeonly buffer Out_ { float outv[]; };   // [S * NS]
layout(push_constant) uniform Push {
    int H; int NS; int G; int R; int C;
    float inv_cell; float win; float cap;
} p;

#include "codebook_window.glsl"

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint h = gl_GlobalInvocationID.x; h < uint(p.H); h += stride) {
        const uint base = (h / uint(p.NS)) * uint(p.G + 1) * uint(p.G + 1), j = h % uint(p.NS);
        const float cs = spins[2u * j], sn = spins[2u * j + 1u];
        float wmin = p.cap;
        for (int r = 0; r < p.R; ++r)
            for (int c = 0; c < p.C; ++c) wmin = min(wmin, window_depth(base, cs, sn, r, c));
        outv[h] = wmin;
    }
}
