#version 450
// SPEC 1 normalised frame on the GPU: centre = mean(xyz), scale = max ||p - centre||,
// xyz -> (xyz - centre) / scale, other columns copied (normals are not scaled).
// One workgroup: a shared-memory tree reduction for the sum, another for the max.
// fp32 throughout; the model itself normalises on the host in double (see
// engine/ops/cloud_normalize.cpp for why).
layout(local_size_x_id = 0) in;  // a power of two

layout(std430, binding = 0) readonly buffer In_ { float x[]; };    // [N, D]
layout(std430, binding = 1) writeonly buffer Out_ { float y[]; };  // [N, D]
layout(std430, binding = 2) writeonly buffer Frame_ { float frame[]; };  // centre xyz, scale
layout(push_constant) uniform Push { uint N; uint D; } p;

shared vec4 red[gl_WorkGroupSize.x];

vec3 point(uint i) { return vec3(x[i * p.D], x[i * p.D + 1u], x[i * p.D + 2u]); }

void reduce(bool is_max) {
    for (uint s = gl_WorkGroupSize.x >> 1u; s > 0u; s >>= 1u) {
        uint t = gl_LocalInvocationID.x;
        if (t < s) red[t] = is_max ? max(red[t], red[t + s]) : red[t] + red[t + s];
        barrier();
    }
}

void main() {
    const uint L = gl_WorkGroupSize.x, tid = gl_LocalInvocationID.x;
    vec3 sum = vec3(0.0);
    for (uint i = tid; i < p.N; i += L) sum += point(i);
    red[tid] = vec4(sum, 0.0);
    barrier();
    reduce(false);
    const vec3 c = red[0].xyz / float(p.N);
    barrier();  // everyone has read red[0] before it is reused
    float m = 0.0;
    for (uint i = tid; i < p.N; i += L) {
        vec3 e = point(i) - c;
        m = max(m, dot(e, e));
    }
    red[tid] = vec4(m);
    barrier();
    reduce(true);
    const float scale = sqrt(red[0].x);
    const float inv = scale > 0.0 ? 1.0 / scale : 1.0;  // identical points: the CPU reference throws
    if (tid == 0u) frame[0] = c.x, frame[1] = c.y, frame[2] = c.z, frame[3] = scale;
    for (uint e = tid; e < p.N * p.D; e += L) {
        uint col = e % p.D;
        y[e] = col < 3u ? (x[e] - c[col]) * inv : x[e];
    }
}
