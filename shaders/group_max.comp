#version 450
// Max over each group of NS consecutive rows: [G * NS, C] -> [G, C]; or, with
// channel_major, from [C, G * NS] (each group's rows contiguous per channel).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer In_ { float x[]; };
layout(std430, binding = 1) writeonly buffer Out_ { float y[]; };
layout(push_constant) uniform Push { uint G; uint NS; uint C; uint channel_major; } p;

void main() {
    const uint total = p.G * p.C;
    for (uint e = gl_GlobalInvocationID.x; e < total; e += gl_NumWorkGroups.x * gl_WorkGroupSize.x) {
        uint g = e / p.C, c = e % p.C;
        // Row r of the group is at base + r * step.
        uint base = p.channel_major != 0u ? c * p.G * p.NS + g * p.NS : g * p.NS * p.C + c;
        uint step = p.channel_major != 0u ? 1u : p.C;
        float m = x[base];
        for (uint j = 1u; j < p.NS; ++j) m = max(m, x[base + j * step]);
        y[e] = m;
    }
}
