// Body of tactile_preprocess.comp (the image through a texel buffer: a gather per
// fetch on CPU drivers) and tactile_preprocess_ssbo.comp (a storage buffer, for
// images past the device's texel-buffer limit); they declare binding 0 and LOAD_IMG.
// SPEC section 2 tactile preprocessing: x = T / 255, centre crop to crop x crop
// (zeros outside the image, torchvision's offsets), bilinear resize to S x S
// (align_corners false, no antialias: PyTorch's source index and lambda rules),
// (x - mean) / std. The image is [B,] H x W x 3 int32, one byte value per element
// (see engine/ops/tactile_preprocess.h). One invocation per 4 output columns of
// one output row, all 3 channels: the columns' source taps are found once, and the
// 4 values of a channel are one vec4 store where S % 4 == 0 (a CPU driver stores
// lane by lane, a branch each: 4 values a branch instead of 1).
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const bool OVEC4 = true;  // S % 4 == 0

layout(std430, binding = 1) writeonly buffer Y_ { vec4 Y4[]; };  // [B][3][S][S]
layout(push_constant) uniform Push { uint H, W, crop, S; int top, left; } p;

const float kMean[3] = float[3](0.485, 0.456, 0.406);
const float kStd[3] = float[3](0.229, 0.224, 0.225);

// Crop-space pixel (cy, cx) of channel c of image b, in [0, 1]; zero outside the image.
float crop_px(uint b, uint c, int cy, int cx) {
    int y = cy + p.top, x = cx + p.left;
    bool ok = y >= 0 && y < int(p.H) && x >= 0 && x < int(p.W);
    int v = LOAD_IMG(ok ? ((b * p.H + uint(y)) * p.W + uint(x)) * 3u + c : 0u);
    return ok ? float(clamp(v, 0, 255)) / 255.0 : 0.0;
}

// Source indices and the weight of the second one along one axis: PyTorch's
// max(crop / S * (o + 0.5) - 0.5, 0), kept exact as the integer 2S times it, so
// a float scale's rounding (~1e-5 at index 300) never shifts the weights. The
// quotient comes from a float division, corrected by one step: CPU devices
// divide integers lane by lane.
void source(uint o, out int i0, out int i1, out float l1) {
    if (p.crop == p.S) { i0 = i1 = int(o); l1 = 0.0; return; }
    int den = 2 * int(p.S);
    int num = max(int(p.crop) * (2 * int(o) + 1) - int(p.S), 0);
    int q = int(float(num) / float(den));
    q += (q + 1) * den <= num ? 1 : 0;
    q -= q * den > num ? 1 : 0;
    i0 = min(q, int(p.crop) - 1);
    i1 = i0 + (i0 < int(p.crop) - 1 ? 1 : 0);
    l1 = clamp(float(num - i0 * den) / float(den), 0.0, 1.0);
}

void main() {
    // x: the quad of columns, y: the output row, z: the image. No integer division:
    // a CPU driver divides lane by lane, and dividing a flat index per 4 outputs
    // cost half of the op's time (docs/performance.md "Tactile preprocessing").
    const uint quads = (p.S + 3u) / 4u;
    const bool live = gl_GlobalInvocationID.x < quads;  // spare lanes compute the last quad, store nothing
    const uint b = gl_WorkGroupID.z, oy = gl_WorkGroupID.y, ox0 = min(gl_GlobalInvocationID.x, quads - 1u) * 4u;
    int y0, y1;
    float ly;
    source(oy, y0, y1, ly);
    int x0[4], x1[4];
    float lx[4];
    [[unroll]] for (uint u = 0u; u < 4u; ++u) source(min(ox0 + u, p.S - 1u), x0[u], x1[u], lx[u]);
    [[unroll]] for (uint c = 0u; c < 3u; ++c) {
        vec4 v;
        [[unroll]] for (uint u = 0u; u < 4u; ++u) {
            const float top = (1.0 - lx[u]) * crop_px(b, c, y0, x0[u]) + lx[u] * crop_px(b, c, y0, x1[u]);
            const float bot = (1.0 - lx[u]) * crop_px(b, c, y1, x0[u]) + lx[u] * crop_px(b, c, y1, x1[u]);
            v[u] = ((1.0 - ly) * top + ly * bot - kMean[c]) / kStd[c];
        }
        const uint e = ((b * 3u + c) * p.S + oy) * p.S + ox0;
        if (!live) continue;
        if (OVEC4) {
            Y4[e / 4u] = v;
        } else {
            [[unroll]] for (uint u = 0u; u < 4u; ++u)
                if (ox0 + u < p.S) Y4[(e + u) / 4u][(e + u) % 4u] = v[u];
        }
    }
}
