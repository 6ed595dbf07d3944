#version 450
// Chamfer distance from the nearest-neighbour distances: workgroup s (one per set
// of a batch) sums its mins[0, Na) and mins[Na, Na + Nb) (each thread a strided
// run, then a tree in shared memory) and writes mean_a + mean_b to result[s].
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Mins_ { float mins[]; };
layout(std430, binding = 1) writeonly buffer Out_ { float result[]; };
layout(push_constant) uniform Push { uint Na; uint Nb; } p;

shared vec2 part[gl_WorkGroupSize.x];

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint set = gl_WorkGroupID.x, base = set * (p.Na + p.Nb);
    vec2 s = vec2(0.0);
    for (uint i = tid; i < p.Na; i += L) s.x += mins[base + i];
    for (uint i = tid; i < p.Nb; i += L) s.y += mins[base + p.Na + i];
    part[tid] = s;
    barrier();
    // Tree over a workgroup size that need not be a power of two.
    for (uint width = L; width > 1u;) {
        uint half_w = (width + 1u) / 2u;
        if (tid < width - half_w) part[tid] += part[tid + half_w];
        width = half_w;
        barrier();
    }
    if (tid == 0u) result[set] = part[0].x / float(p.Na) + part[0].y / float(p.Nb);
}
