#version 450
// Normalises a log score in one workgroup: log = v - logsumexp(v) (max, then the sum
// of exp(v - max), each a tree in shared memory) and prob = exp(log).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer In_ { float v[]; };
layout(std430, binding = 1) writeonly buffer Log_ { float logp[]; };
layout(std430, binding = 2) writeonly buffer Prob_ { float prob[]; };
layout(push_constant) uniform Push { uint M; } p;

shared float part[gl_WorkGroupSize.x];

// Reduces part[] to part[0] (sum or max); the workgroup size need not be a power of two.
void reduce(bool is_max) {
    const uint tid = gl_LocalInvocationID.x;
    for (uint width = gl_WorkGroupSize.x; width > 1u;) {
        uint half_w = (width + 1u) / 2u;
        if (tid < width - half_w)
            part[tid] = is_max ? max(part[tid], part[tid + half_w]) : part[tid] + part[tid + half_w];
        width = half_w;
        barrier();
    }
}

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    float m = -1.0 / 0.0;
    for (uint i = tid; i < p.M; i += L) m = max(m, v[i]);
    part[tid] = m;
    barrier();
    reduce(true);
    m = part[0];
    barrier();
    float s = 0.0;
    for (uint i = tid; i < p.M; i += L) s += exp(v[i] - m);
    part[tid] = s;
    barrier();
    reduce(false);
    float lse = m + log(part[0]);
    for (uint i = tid; i < p.M; i += L) {
        float l = v[i] - lse;
        logp[i] = l;
        prob[i] = exp(l);
    }
}
