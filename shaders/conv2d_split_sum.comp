#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_GOOGLE_include_directive : require
// conv2d's second pass where it splits the input channels (KSPLIT in conv2d.glsl):
// y = act(sum of the parts + bias + residual), the parts added in order 0..KSPLIT-1
// (every run sums the same way). One output per invocation, grid-stride.
#include "act.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint KSPLIT = 2;
layout(constant_id = 2) const uint ACT = 0;
layout(constant_id = 3) const bool HAS_BIAS = false;
layout(constant_id = 4) const bool HAS_RES = false;

layout(std430, binding = 0) readonly buffer P_ { float P[]; };  // [KSPLIT][N][Cout][OH][OW]
layout(std430, binding = 1) readonly buffer B_ { float Bias[]; };
layout(std430, binding = 2) readonly buffer R_ { float Res[]; };
layout(std430, binding = 3) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push {
    uint total;  // N * Cout * OH * OW
    uint Cout;
    uint plane;  // OH * OW
    float slope;
} p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < p.total; i += stride) {
        float v = P[i];
        [[unroll]] for (uint z = 1; z < KSPLIT; ++z) v += P[z * p.total + i];
        if (HAS_BIAS) v += Bias[(i / p.plane) % p.Cout];
        if (HAS_RES) v += Res[i];
        Y[i] = apply_act(v, ACT, p.slope);
    }
}
