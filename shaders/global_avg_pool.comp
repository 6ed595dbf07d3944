#version 450
// Mean of each H x W plane of an NCHW tensor -> [N, C, 1, 1]; one invocation per plane.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint planes, hw; } p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < p.planes; i += stride) {
        // Four partial sums: shorter dependency chains, and less rounding than one.
        vec4 s = vec4(0.0);
        uint base = i * p.hw, j = 0;
        for (; j + 4 <= p.hw; j += 4) s += vec4(X[base + j], X[base + j + 1], X[base + j + 2], X[base + j + 3]);
        for (; j < p.hw; ++j) s.x += X[base + j];
        Y[i] = ((s.x + s.y) + (s.z + s.w)) / float(p.hw);
    }
}
