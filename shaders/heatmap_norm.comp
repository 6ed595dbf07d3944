#version 450
// Min-max normalisation of the heat-map in place, one workgroup per map of a
// batch: a min/max tree in shared memory, then s = (s - lo) / (hi - lo); all
// zeros when hi == lo.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) buffer Heat_ { float heat[]; };
layout(push_constant) uniform Push { uint P; } p;

shared vec2 part[gl_WorkGroupSize.x];  // (min, max)

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint base = gl_WorkGroupID.x * p.P;
    vec2 m = vec2(1.0 / 0.0, -1.0 / 0.0);
    for (uint i = base + tid; i < base + p.P; i += L) m = vec2(min(m.x, heat[i]), max(m.y, heat[i]));
    part[tid] = m;
    barrier();
    for (uint width = L; width > 1u;) {
        uint half_w = (width + 1u) / 2u;
        if (tid < width - half_w) {
            vec2 o = part[tid + half_w];
            part[tid] = vec2(min(part[tid].x, o.x), max(part[tid].y, o.y));
        }
        width = half_w;
        barrier();
    }
    const float lo = part[0].x, hi = part[0].y;
    for (uint i = base + tid; i < base + p.P; i += L) heat[i] = hi == lo ? 0.0 : (heat[i] - lo) / (hi - lo);
}
