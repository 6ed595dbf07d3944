#version 450
#extension GL_GOOGLE_include_directive : require
// y = act(x), elementwise; grid-stride so any n fits the device's group limits.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint ACT = 0;
#include "act.glsl"

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint n; float slope; } p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < p.n; i += stride)
        Y[i] = apply_act(X[i], ACT, p.slope);
}
