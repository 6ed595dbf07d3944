#version 450
// Grouping (SPEC 2): row m = (centre s, slot j) of the output holds
// [features of point idx[m], xyz of point idx[m] - centre s] (features first).
// One invocation per output element (grid-stride).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Points_ { float pts[]; };    // [P, D], xyz = columns 0..2
layout(std430, binding = 1) readonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 2) readonly buffer Index_ { int idx[]; };       // [S, NS]
layout(std430, binding = 3) readonly buffer Feat_ { float feat[]; };     // [P, DF], columns FB.. used
layout(std430, binding = 4) writeonly buffer Out_ { float outv[]; };     // [S * NS, CF + 3]
layout(push_constant) uniform Push { uint rows; uint NS; uint P; uint D; uint DF; uint FB; uint CF; } p;

void main() {
    const uint K = p.CF + 3u;
    const uint total = p.rows * K;
    for (uint e = gl_GlobalInvocationID.x; e < total; e += gl_NumWorkGroups.x * gl_WorkGroupSize.x) {
        uint m = e / K, k = e % K;
        uint q = min(uint(idx[m]), p.P - 1u);  // in range whatever the indices hold
        outv[e] = k < p.CF ? feat[q * p.DF + p.FB + k] : pts[q * p.D + (k - p.CF)] - centre[3u * (m / p.NS) + (k - p.CF)];
    }
}
