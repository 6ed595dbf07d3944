#version 450
#extension GL_GOOGLE_include_directive : require
// GMA decoder output, per row of 6: xyz = tanh(o[0:3]), n = o[3:6] / max(||o[3:6]||, 1e-6).
layout(local_size_x_id = 0) in;
#include "act.glsl"

layout(std430, binding = 0) readonly buffer O_ { float O[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint rows; } p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint r = gl_GlobalInvocationID.x; r < p.rows; r += stride) {
        uint b = r * 6u;
        for (uint i = 0; i < 3u; ++i) Y[b + i] = apply_act(O[b + i], ACT_TANH, 0.0);
        vec3 n = vec3(O[b + 3u], O[b + 4u], O[b + 5u]);
        n /= max(length(n), 1e-6);
        Y[b + 3u] = n.x;
        Y[b + 4u] = n.y;
        Y[b + 5u] = n.z;
    }
}
