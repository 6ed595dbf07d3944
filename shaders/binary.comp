#version 450
// out = a (op) b, with b repeated when it is shorter (b's shape is a suffix of a's).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint OP = 0;  // 0 add, 1 mul, 2 sub

layout(std430, binding = 0) readonly buffer A_ { float A[]; };
layout(std430, binding = 1) readonly buffer B_ { float B[]; };
layout(std430, binding = 2) writeonly buffer O_ { float O[]; };
layout(push_constant) uniform Push { uint n; uint nb; } p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < p.n; i += stride) {
        float b = B[i % p.nb];
        O[i] = OP == 0u ? A[i] + b : OP == 1u ? A[i] * b : A[i] - b;
    }
}
