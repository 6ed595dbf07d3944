#version 450
// One pass of top-K selection by (score, index), ties to the lower index.
// Each workgroup sorts a chunk of S keys in shared memory (bitonic) and keeps the
// first K: S / K chunks shrink to one list per pass, so a few passes reduce 100k
// candidates to K. Key = (float bits of the score, index): scores are >= 0, so
// their bits order like the floats; padding keys (~0, ~0) sort last, NaN before them.
// FIRST: the items are candidates [n, 3] and the score S_i = ||c^p - c_i||^2 is
// computed here as (dx*dx + dy*dy) + dz*dz in single precision, each operation
// rounded once (`precise`: no fma), exactly as the reference does.
// FINAL: write index[K] and score[K] instead of keys.
// Workgroup y = the contact (row) of a batch: its contact, key lists (src_stride /
// dst_stride words apart; the candidates are shared) and outputs (K apart).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint S = 256;  // chunk: a power of two >= 2K
layout(constant_id = 2) const bool FIRST = true;
layout(constant_id = 3) const bool FINAL = true;

layout(std430, binding = 0) readonly buffer Contact_ { float contact[]; };
layout(std430, binding = 1) readonly buffer Src_ { uint src[]; };  // candidates (float bits) or keys
layout(std430, binding = 2) buffer Dst_ { uint dst[]; };           // keys of this pass
layout(std430, binding = 3) buffer Index_ { int index[]; };
layout(std430, binding = 4) buffer Score_ { float score[]; };
layout(push_constant) uniform Push { uint n; uint K; uint src_stride; uint dst_stride; } p;

shared uvec2 keys[S];

bool before(uvec2 a, uvec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

void main() {
    const uint L = gl_WorkGroupSize.x;
    const uint tid = gl_LocalInvocationID.x;
    const uint base = gl_WorkGroupID.x * S;
    const uint row = gl_WorkGroupID.y;
    const uint src0 = row * p.src_stride, dst0 = row * p.dst_stride, out0 = row * p.K;
    for (uint i = tid; i < S; i += L) {
        uint gi = base + i;
        uvec2 key = uvec2(0xFFFFFFFFu);
        if (gi < p.n) {
            if (FIRST) {
                precise float dx = uintBitsToFloat(src[gi * 3u]) - contact[3u * row];
                precise float dy = uintBitsToFloat(src[gi * 3u + 1u]) - contact[3u * row + 1u];
                precise float dz = uintBitsToFloat(src[gi * 3u + 2u]) - contact[3u * row + 2u];
                precise float s = (dx * dx + dy * dy) + dz * dz;
                key = uvec2(floatBitsToUint(s), gi);
            } else {
                key = uvec2(src[src0 + 2u * gi], src[src0 + 2u * gi + 1u]);
            }
        }
        keys[i] = key;
    }
    barrier();
    for (uint size = 2u; size <= S; size <<= 1u) {
        for (uint stride = size >> 1u; stride > 0u; stride >>= 1u) {
            for (uint t = tid; t < S / 2u; t += L) {
                uint i = 2u * stride * (t / stride) + t % stride;
                uint j = i + stride;
                uvec2 a = keys[i], b = keys[j];
                if (before(b, a) == ((i & size) == 0u)) {
                    keys[i] = b;
                    keys[j] = a;
                }
            }
            barrier();
        }
    }
    for (uint i = tid; i < p.K; i += L) {
        uvec2 k = keys[i];
        if (FINAL) {
            index[out0 + i] = int(k.y);
            score[out0 + i] = uintBitsToFloat(k.x);
        } else {
            uint o = gl_WorkGroupID.x * p.K + i;
            dst[dst0 + 2u * o] = k.x;
            dst[dst0 + 2u * o + 1u] = k.y;
        }
    }
}
