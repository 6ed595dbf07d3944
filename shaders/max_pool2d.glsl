// Body of max_pool2d.comp (texel-buffer input) and max_pool2d_ssbo.comp (storage
// buffer, for inputs beyond the device's texel-buffer limit); they declare
// binding 0 and LOAD_X.
//
// PyTorch MaxPool2d (dilation 1, floor mode): padding never wins the max. One
// invocation per output row (grid-stride over plane x OH rows), walking the row:
// integer division, which CPU devices do lane by lane, happens once per row. The
// kernel is a specialization constant so the window unrolls into branch-free
// fetches and selects.
layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint KH = 3;
layout(constant_id = 2) const uint KW = 3;

// OVEC4 (OW % 4 == 0): 4 outputs a step from one window of 3 SW + KW columns per
// kernel row (27 fetches instead of 36 for ResNet's 3x3 / 2) and one vec4 store (a
// CPU driver stores lane by lane, a branch each); else one output a step.
layout(constant_id = 3) const uint SW = 1;  // the column stride
layout(constant_id = 4) const bool OVEC4 = false;
const uint U = OVEC4 ? 4u : 1u;
const uint IC = (U - 1u) * SW + KW;

layout(std430, binding = 1) writeonly buffer Y_ { float Y[]; };
layout(std430, binding = 2) writeonly buffer Y4_ { vec4 Y4[]; };  // binding 1 as vec4s
layout(push_constant) uniform Push { uint planes, H, W, OH, OW, sh, sw; int ph, pw; } p;

void main() {
    uint rows = p.planes * p.OH;
    uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    for (uint row = gl_GlobalInvocationID.x; row < rows; row += stride) {
        uint plane = row / p.OH, oy = row % p.OH;
        int y0 = int(oy * p.sh) - p.ph;
        bool rowok[KH];
        [[unroll]] for (uint ky = 0; ky < KH; ++ky) rowok[ky] = y0 + int(ky) >= 0 && y0 + int(ky) < int(p.H);
        int base = int(plane * p.H * p.W) + y0 * int(p.W);
        // U outputs a step from one window of IC columns per kernel row.
        for (uint ox = 0; ox < p.OW; ox += U) {
            const int x0 = int(ox * SW) - p.pw;
            vec4 m = vec4(uintBitsToFloat(0xff800000u));  // -inf
            [[unroll]] for (uint ky = 0; ky < KH; ++ky) {
                float v[IC];
                bool ok[IC];
                [[unroll]] for (uint i = 0; i < IC; ++i) {
                    const int x = x0 + int(i);
                    ok[i] = rowok[ky] && x >= 0 && x < int(p.W);
                    v[i] = LOAD_X(ok[i] ? base + int(ky * p.W) + x : 0);
                }
                [[unroll]] for (uint u = 0; u < U; ++u)
                    [[unroll]] for (uint kx = 0; kx < KW; ++kx)
                        m[u] = ok[u * SW + kx] ? max(m[u], v[u * SW + kx]) : m[u];
            }
            if (OVEC4) Y4[(row * p.OW + ox) / 4u] = m;
            else Y[row * p.OW + ox] = m.x;
        }
    }
}
