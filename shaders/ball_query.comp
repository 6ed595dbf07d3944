#version 450
// Ball query (SPEC 2): for each centre, the first NS points in index order with
// squared distance <= r2, the remaining slots filled with the first one found.
// One thread per centre scans the cloud in index order (the order is the
// answer, and it stops as soon as NS are found); the workgroup stages the
// cloud through shared memory one tile of L points at a time and stops when
// every thread is done. Distances as the reference computes them: (dx*dx +
// dy*dy) + dz*dz in single precision, one rounding per operation (`precise`),
// and r2 = float(r) * float(r) computed on the host in float.
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Points_ { float pts[]; };   // [N, D], xyz = columns 0..2
layout(std430, binding = 1) readonly buffer Centre_ { float centre[]; };  // [S, 3]
layout(std430, binding = 2) writeonly buffer Index_ { int index[]; };    // [S, NS]
layout(push_constant) uniform Push { uint N; uint D; uint S; uint NS; float r2; } p;

shared vec3 tile[gl_WorkGroupSize.x];
shared uint busy[2];  // threads still searching, by tile parity

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint s = gl_WorkGroupID.x * L + tid;
    const bool valid = s < p.S;
    vec3 c = valid ? vec3(centre[3u * s], centre[3u * s + 1u], centre[3u * s + 2u]) : vec3(0.0);
    uint found = 0u, first = 0u;
    bool searching = valid;
    if (tid < 2u) busy[tid] = 0u;
    barrier();
    for (uint t = 0u, base = 0u; base < p.N; ++t, base += L) {
        uint i = base + tid;
        if (i < p.N) tile[tid] = vec3(pts[i * p.D], pts[i * p.D + 1u], pts[i * p.D + 2u]);
        barrier();
        if (searching) {
            uint n = min(L, p.N - base);
            for (uint j = 0u; j < n; ++j) {
                vec3 q = tile[j];
                precise float dx = q.x - c.x;
                precise float dy = q.y - c.y;
                precise float dz = q.z - c.z;
                precise float d = (dx * dx + dy * dy) + dz * dz;
                if (d <= p.r2) {
                    if (found == 0u) first = base + j;
                    index[s * p.NS + found] = int(base + j);
                    if (++found == p.NS) break;
                }
            }
            searching = found < p.NS;
            if (searching) atomicAdd(busy[t & 1u], 1u);
        }
        if (tid == 0u) busy[(t + 1u) & 1u] = 0u;  // the next tile's counter, read two barriers later
        barrier();
        if (busy[t & 1u] == 0u) break;  // uniform: every thread reads the same count
    }
    // Fill; `first` stays 0 only if nothing was found (NaN input), which keeps indices in range.
    if (valid)
        for (uint k = found; k < p.NS; ++k) index[s * p.NS + k] = int(first);
}
