#version 450
// Copies one input [rows, width] into columns [col0, col0 + width) of an
// output [rows, out_width]; concat along the last axis is one dispatch per input.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint rows; uint width; uint out_width; uint col0; } p;

void main() {
    uint n = p.rows * p.width;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < n; i += stride) {
        uint r = i / p.width, c = i % p.width;
        Y[r * p.out_width + p.col0 + c] = X[i];
    }
}
