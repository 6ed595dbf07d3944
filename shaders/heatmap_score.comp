#version 450
// Heat-map scores (SPEC 3), one point per thread: w = the rank (1-based) of the
// nearest top-K centre, lowest rank on a tie, s_p = exp(-||p - c*_w||) / w.
// With the symmetry prior each centre is replaced by its T copies
// R_t c + t_t (affine 3x4 rows from the host); every copy keeps the centre's rank.
// Distances are compared after the square root, as the reference does.
// Workgroup y = the row of a batch: its top-K at index[y * K], its map at heat[y * P].
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Cloud_ { float cloud[]; };   // [P, D]
layout(std430, binding = 1) readonly buffer Cand_ { float cand[]; };     // [M, 3]
layout(std430, binding = 2) readonly buffer Index_ { int index[]; };     // [B, K]
layout(std430, binding = 3) readonly buffer Sym_ { float sym[]; };       // [T, 12] when T > 0
layout(std430, binding = 4) writeonly buffer Heat_ { float heat[]; };    // [B, P]
layout(push_constant) uniform Push { uint P; uint D; uint M; uint K; uint T; } p;

void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    const uint row = gl_WorkGroupID.y;
    for (uint i = gl_GlobalInvocationID.x; i < p.P; i += stride) {
        vec3 pt = vec3(cloud[i * p.D], cloud[i * p.D + 1u], cloud[i * p.D + 2u]);
        float best = 1.0 / 0.0;
        uint w = 1u;
        for (uint j = 0u; j < p.K; ++j) {
            uint ci = min(uint(max(index[row * p.K + j], 0)), p.M - 1u);  // never read outside the buffer
            vec3 c = vec3(cand[ci * 3u], cand[ci * 3u + 1u], cand[ci * 3u + 2u]);
            for (uint t = 0u; t < max(p.T, 1u); ++t) {
                vec3 ct = c;
                if (p.T > 0u) {
                    uint b = t * 12u;
                    ct = vec3(dot(vec3(sym[b], sym[b + 1u], sym[b + 2u]), c) + sym[b + 3u],
                              dot(vec3(sym[b + 4u], sym[b + 5u], sym[b + 6u]), c) + sym[b + 7u],
                              dot(vec3(sym[b + 8u], sym[b + 9u], sym[b + 10u]), c) + sym[b + 11u]);
                }
                vec3 e = pt - ct;
                float d = sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
                if (d < best) {  // strict: an equal distance keeps the lower rank
                    best = d;
                    w = j + 1u;
                }
            }
        }
        heat[row * p.P + i] = exp(-best) / float(w);
    }
}
