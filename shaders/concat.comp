#version 450
// Copies one input [rows, width] into columns [col0, col0 + width) of an output
// [rows, out_width]; concat along the last axis is one dispatch per input. The
// grid is (column, row): no integer division (a CPU driver divides lane by lane,
// and split a flat index per element). VEC4 (width, out_width and col0 multiples
// of 4): a column is 4 floats, one vec4 load and store.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool VEC4 = false;

layout(std430, binding = 0) readonly buffer X_ { float X[]; };
layout(std430, binding = 1) readonly buffer X4_ { vec4 X4[]; };  // binding 0 as vec4s
layout(std430, binding = 2) writeonly buffer Y_ { float Y[]; };
layout(std430, binding = 3) writeonly buffer Y4_ { vec4 Y4[]; };  // binding 2 as vec4s
layout(push_constant) uniform Push { uint rows; uint width; uint out_width; uint col0; } p;

void main() {
    const uint c = gl_GlobalInvocationID.x, w = VEC4 ? p.width / 4u : p.width;
    if (c >= w) return;
    for (uint r = gl_WorkGroupID.y; r < p.rows; r += gl_NumWorkGroups.y) {
        if (VEC4) Y4[(r * p.out_width + p.col0) / 4u + c] = X4[r * w + c];
        else Y[r * p.out_width + p.col0 + c] = X[r * p.width + c];
    }
}
