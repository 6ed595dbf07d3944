#version 450
#extension GL_EXT_control_flow_attributes : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_KHR_shader_subgroup_vote : require
// ball_query.comp without shared memory or barriers, where the device has
// subgroup shuffles (SG <= 32): each subgroup scans the cloud SG points at a
// time, lane l fetching point base + l and every lane taking them in index order
// by shuffles at constant lane indices (on lavapipe each shared-memory load of
// the tiled shader was a loop over the lanes). A chunk's hits become a bit mask
// first and are stored afterwards, so a chunk without hits stores nothing; the
// subgroup stops when all its centres are done. Same distances (`precise`),
// order and fill as ball_query.comp.
layout(local_size_x_id = 0) in;  // whole subgroups
layout(constant_id = 1) const uint SG = 8;  // the device's subgroup size

layout(binding = 0) uniform samplerBuffer P;  // [N, D] as R32F, xyz = columns 0..2
layout(std430, binding = 1) readonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 2) writeonly buffer Index_ { int index[]; };    // [S, NS]
layout(push_constant) uniform Push { uint N; uint D; uint S; uint NS; float r2; } p;

void main() {
    const uint s = gl_GlobalInvocationID.x;
    const bool valid = s < p.S;
    const uint sc = min(s, p.S - 1u);  // lanes past S scan along (every lane takes part in the shuffles)
    const vec3 c = vec3(centre[3u * sc], centre[3u * sc + 1u], centre[3u * sc + 2u]);
    uint found = 0u, first = 0u;
    bool searching = valid;
    for (uint base = 0u; base < p.N && subgroupAny(searching); base += SG) {
        const uint i = min(base + gl_SubgroupInvocationID, p.N - 1u);
        const vec3 q = vec3(texelFetch(P, int(i * p.D)).x, texelFetch(P, int(i * p.D + 1u)).x,
                            texelFetch(P, int(i * p.D + 2u)).x);
        uint hits = 0u;
        [[unroll]] for (uint j = 0u; j < SG; ++j) {
            const vec3 qj = subgroupShuffle(q, j);
            precise float dx = qj.x - c.x;
            precise float dy = qj.y - c.y;
            precise float dz = qj.z - c.z;
            precise float d = (dx * dx + dy * dy) + dz * dz;
            if (d <= p.r2 && base + j < p.N) hits |= 1u << j;
        }
        while (searching && hits != 0u) {  // in index order, until the centre has NS
            const uint j = uint(findLSB(hits));
            hits &= hits - 1u;
            if (found == 0u) first = base + j;
            index[s * p.NS + found] = int(base + j);
            searching = ++found < p.NS;
        }
    }
    // Fill; `first` stays 0 only if nothing was found (NaN input), which keeps indices in range.
    if (valid)
        for (uint k = found; k < p.NS; ++k) index[s * p.NS + k] = int(first);
}
