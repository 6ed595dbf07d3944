#version 450
// group_linear's weights W [K][N] copied into column blocks of `nc` columns,
// block b at float offset b * stride as [K][width of b], so each block is one
// contiguous range a uniform buffer can bind (group_linear.cpp). Grid-stride.
layout(local_size_x_id = 0) in;
layout(std430, binding = 0) readonly buffer W_ { float W[]; };
layout(std430, binding = 1) writeonly buffer B_ { float blocks[]; };
layout(push_constant) uniform Push { uint K; uint N; uint nc; uint stride; } p;

void main() {
    const uint total = p.K * p.N, step = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint i = gl_GlobalInvocationID.x; i < total; i += step) {
        const uint k = i / p.N, n = i % p.N, b = n / p.nc, j = n % p.nc;
        const uint width = min(p.nc, p.N - b * p.nc);
        blocks[b * p.stride + k * width + j] = W[i];
    }
}
