#version 450
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// pose_evidence.glsl with its tables (samples, dense surface, cells, spins, fields) read through
// uniform texel buffers: on a CPU driver a texel fetch is a gather, where a storage-buffer
// read at an offset Mesa cannot prove uniform is a loop over the lanes that puts each
// lane's value into its vector through the stack; with AVX2 only (no masked inserts) every
// such insert stalls on store forwarding (docs/multitouch.md, "The tables as texels").
layout(binding = 0) uniform samplerBuffer Smp4;    // RGBA32F, [S, 12]: point, 0, normal, 0, t1, 0
layout(binding = 1) uniform samplerBuffer Dense4;  // RGBA32F, [D, 8]: point, sample, normal, 0
layout(binding = 2) uniform isamplerBuffer Cells;  // R32I, [V, 2]
layout(binding = 3) uniform samplerBuffer Spins;  // R32F, [NS, 2]: cos, sin
layout(binding = 5) uniform samplerBuffer Fields;  // R32F, [F, H]
#define LOAD_SMP(i) texelFetch(Smp4, int(i))
#define LOAD_DENSE(i) texelFetch(Dense4, int(i))
#define LOAD_CELL(c) ivec2(texelFetch(Cells, 2 * (c)).x, texelFetch(Cells, 2 * (c) + 1).x)
#define LOAD_SPIN(j) vec2(texelFetch(Spins, 2 * int(j)).x, texelFetch(Spins, 2 * int(j) + 1).x)
#define LOAD_FIELD(i) texelFetch(Fields, int(i)).x
#include "pose_evidence.glsl"
