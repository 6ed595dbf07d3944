// The heat-map of heatmap_subgroup.comp, shared with retrieve_subgroup.comp:
// one subgroup scores a row's P points (each lane every S-th point), keeps its
// min and max, a butterfly of shuffles gives the row's, and each lane
// normalises the points it wrote (its own writes: no barrier needed). The
// includer declares KR, the cloud (R32F texel buffer), cand, index, sym and
// heat buffers and p {P, D, M, K, T}, and with KR > 0 fills hm_centre with the
// K centres (rank j + 1 at j), the same in every lane: read once, not per
// point, and not passed between lanes either, since on a CPU driver a shuffle
// costs more than the distance it feeds.
vec3 hm_centre[KR > 0u ? KR : 1u];

// Candidate ci (clamped into the buffer) as centre j.
void hm_set_centre(uint j, uint ci) {
    ci = min(ci, p.M - 1u);
    hm_centre[j] = vec3(cand[ci * 3u], cand[ci * 3u + 1u], cand[ci * 3u + 2u]);
}

void heat_row(uint row) {
    const uint S = gl_SubgroupSize, lane = gl_SubgroupInvocationID;
    vec2 m = vec2(1.0 / 0.0, -1.0 / 0.0);
    // Every lane runs every round (the shuffles need them all); a lane past the
    // end recomputes the last point and neither stores nor counts it.
    for (uint i0 = 0u; i0 < p.P; i0 += S) {
        const bool live = i0 + lane < p.P;
        const uint i = min(i0 + lane, p.P - 1u);
        vec3 pt = vec3(texelFetch(cloud, int(i * p.D)).x, texelFetch(cloud, int(i * p.D + 1u)).x,
                       texelFetch(cloud, int(i * p.D + 2u)).x);
        float best = 1.0 / 0.0;
        uint w = 1u;
        if (KR > 0u) {
            [[unroll]] for (uint j = 0u; j < KR; ++j) {
                const vec3 e = pt - hm_centre[j];
                const float d = sqrt((e.x * e.x + e.y * e.y) + e.z * e.z);
                if (d < best) {  // strict: an equal distance keeps the lower rank
                    best = d;
                    w = j + 1u;
                }
            }
        }
        for (uint j = 0u; j < (KR > 0u ? 0u : p.K); ++j) {
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
        const float s = exp(-best) / float(w);
        if (live) {
            heat[row * p.P + i] = s;
            m = vec2(min(m.x, s), max(m.y, s));
        }
    }
    for (uint o = 1u; o < S; o <<= 1u) {
        const vec2 other = subgroupShuffleXor(m, o);
        m = vec2(min(m.x, other.x), max(m.y, other.y));
    }
    for (uint i = lane; i < p.P; i += S) {
        const uint at = row * p.P + i;
        heat[at] = m.y == m.x ? 0.0 : (heat[at] - m.x) / (m.y - m.x);
    }
}
