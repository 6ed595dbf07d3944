// The top-K selection of topk_subgroup.comp, shared with retrieve_subgroup.comp.
// The includer declares K (a constant <= 16) and `tk_cand`, the candidates [n, 3]
// as an R32F texel buffer. Keys are (float bits of the score, index): ties go
// to the lower index and NaN after every number.
// Each lane scores every S-th candidate and keeps its K best keys sorted in
// registers; then each topk_pop() takes the smallest head over the subgroup by
// a butterfly of shuffles (the same key in every lane) and pops it from its
// lane. Why: topk.comp's bitonic sort reads shared memory at per-lane addresses
// behind log2(S)^2 / 2 barriers, which on a CPU driver costs far more than
// scanning a cloud.
uvec2 tk_best[K];

bool tk_before(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void topk_scan(vec3 c, uint n) {
    const uint S = gl_SubgroupSize, lane = gl_SubgroupInvocationID;
    for (uint j = 0u; j < K; ++j) tk_best[j] = uvec2(0xFFFFFFFFu);
    for (uint i0 = 0u; i0 < n; i0 += S) {
        const uint i = i0 + lane;
        if (i >= n) break;
        // (dx*dx + dy*dy) + dz*dz, each operation rounded once, as the reference.
        precise float dx = texelFetch(tk_cand, int(3u * i)).x - c.x;
        precise float dy = texelFetch(tk_cand, int(3u * i + 1u)).x - c.y;
        precise float dz = texelFetch(tk_cand, int(3u * i + 2u)).x - c.z;
        precise float s = (dx * dx + dy * dy) + dz * dz;
        uvec2 cur = uvec2(floatBitsToUint(s), i);
        for (uint j = 0u; j < K; ++j) {  // insertion into the sorted list, branch-free
            const bool lt = tk_before(cur, tk_best[j]);
            const uvec2 t = tk_best[j];
            tk_best[j] = lt ? cur : t;
            cur = lt ? t : cur;
        }
    }
}

uvec2 topk_pop() {
    uvec2 m = tk_best[0];
    for (uint o = 1u; o < gl_SubgroupSize; o <<= 1u) {
        const uvec2 other = subgroupShuffleXor(m, o);
        m = tk_before(other, m) ? other : m;
    }
    if (tk_best[0] == m) {  // the one lane holding it (keys are unique: they carry the index)
        for (uint j = 0u; j + 1u < K; ++j) tk_best[j] = tk_best[j + 1u];
        tk_best[K - 1u] = uvec2(0xFFFFFFFFu);
    }
    return m;
}
