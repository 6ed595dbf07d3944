#version 450
// SPEC section 2 tactile preprocessing: x = T / 255, centre crop to crop x crop
// (zeros outside the image, torchvision's offsets), bilinear resize to S x S
// (align_corners false, no antialias: PyTorch's source index and lambda rules),
// (x - mean) / std. The image is [B,] H x W x 3 int32, one byte value per element
// (see engine/ops/tactile_preprocess.h); output rows run over (b, channel, y).
layout(local_size_x_id = 0) in;

layout(std430, binding = 0) readonly buffer Img_ { int img[]; };
layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(push_constant) uniform Push { uint H, W, crop, S; int top, left; uint rows; } p;

const float kMean[3] = float[3](0.485, 0.456, 0.406);
const float kStd[3] = float[3](0.229, 0.224, 0.225);

// Crop-space pixel (cy, cx) of channel c of image b, in [0, 1]; zero outside the image.
float crop_px(uint b, uint c, int cy, int cx) {
    int y = cy + p.top, x = cx + p.left;
    bool ok = y >= 0 && y < int(p.H) && x >= 0 && x < int(p.W);
    int v = img[ok ? ((b * p.H + uint(y)) * p.W + uint(x)) * 3u + c : 0u];
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

// One invocation per output row (grid-stride over B x 3 x S rows), walking the row.
void main() {
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint row = gl_GlobalInvocationID.x; row < p.rows; row += stride) {
        uint b = row / (3u * p.S), c = row / p.S % 3u, oy = row % p.S;
        int y0, y1;
        float ly;
        source(oy, y0, y1, ly);
        for (uint ox = 0; ox < p.S; ++ox) {
            int x0, x1;
            float lx;
            source(ox, x0, x1, lx);
            float top = (1.0 - lx) * crop_px(b, c, y0, x0) + lx * crop_px(b, c, y0, x1);
            float bot = (1.0 - lx) * crop_px(b, c, y1, x0) + lx * crop_px(b, c, y1, x1);
            float v = (1.0 - ly) * top + ly * bot;
            Y[row * p.S + ox] = (v - kMean[c]) / kStd[c];
        }
    }
}
