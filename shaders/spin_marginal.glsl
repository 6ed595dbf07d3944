// Body of spin_marginal.comp (prob as a texel buffer) and spin_marginal_ssbo.comp (past
// the texel limit); they declare binding 0 and LOAD_PROB.
// out[s] = sum over the NS spins of prob[s * NS + j] (the belief at each surface sample).
layout(local_size_x_id = 0) in;
layout(std430, binding = 1) writeonly buffer Out_ { float outv[]; };
layout(push_constant) uniform Push { uint S; uint NS; } p;

void main() {
    const uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint s = gl_GlobalInvocationID.x; s < p.S; s += stride) {
        float acc = 0.0;
        for (uint j = 0u; j < p.NS; ++j) acc += LOAD_PROB(s * p.NS + j);
        outv[s] = acc;
    }
}
