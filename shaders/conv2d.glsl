// Body of conv2d.comp (texel-buffer reads) and conv2d_ssbo.comp (storage-buffer
// reads, for tensors beyond the device's texel-buffer limit). They declare
// bindings 0-4, 6 and 8 (x, w, w as vec4, bias, residual, x as vec4, residual as
// vec4) and the LOAD_* macros (LOAD_X4 / LOAD_RES4 only where XVEC4 / YVEC4 can be
// set); bindings 5 and 7 are the output, as floats and as vec4s.
//
// y = act(conv2d(x, w) + bias + residual), NCHW, PyTorch semantics (cross-correlation,
// zero padding). Implicit GEMM with register tiling: each invocation owns a block of
// TM output channels x R rows x C columns of one image, and per input channel
// loads the (R-1)*SH+KH x (C-1)*SW+KW input window once and the KH*KW*TM weights
// once, then does KH*KW*TM*R*C fmas from registers. Tile sizes, kernel, stride and
// the epilogue are specialization constants (the host picks them per device and
// shape, see engine/ops/conv2d_tiles.cpp), so every loop here is unrolled. No shared
// memory: on CPU devices (lavapipe) shared-memory loads cost more than texel
// fetches, and the register block already reuses every loaded value TM or R*C times.
#include "act.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint TM = 8;    // output channels per invocation, multiple of 4
layout(constant_id = 2) const uint R = 2;     // output rows per invocation
layout(constant_id = 3) const uint C = 4;     // output columns per invocation
layout(constant_id = 4) const uint KH = 3;
layout(constant_id = 5) const uint KW = 3;
layout(constant_id = 6) const uint SH = 1;
layout(constant_id = 7) const uint SW = 1;
// Weight layout: 0 = [Cout][Cin][KH][KW] (PyTorch), 1 = [Cin][KH][KW][Cout] read
// one float at a time, 2 = the same read as vec4 (4 output channels per load;
// needs Cout % 4 == 0).
layout(constant_id = 8) const uint WMODE = 0;
// Epilogue options, constant so that the unrolled stores carry no branches.
layout(constant_id = 9) const uint ACT = 0;         // act.glsl code
layout(constant_id = 10) const bool HAS_BIAS = false;
layout(constant_id = 11) const bool HAS_RES = false;
layout(constant_id = 12) const bool GUARD_CO = false;  // Cout < TM: skip channels past Cout
// Read each input window row as whole vec4s (LOAD_X4, needs numel(x) % 4 == 0):
// ~(IC + 6) / 4 fetches instead of IC, each lane shifting by its own offset mod 4.
layout(constant_id = 13) const bool XVEC4 = false;
// Kernel rows per step: KH, or 1 for kernels above 3x3, whose full window and
// weights would not stay in registers through a chain of KH*KW fmas (both unroll).
layout(constant_id = 14) const uint KHB = 3;
// With XVEC4: the window's offset mod 4 when the host knows it is the same for
// every invocation (row length and block origins multiples of 4), else 4: each
// invocation shifts by its own offset with selects.
layout(constant_id = 15) const uint XSHIFT = 4;
// Store (and read the residual) 4 outputs at a time: needs OW % 4 == 0 and
// C % 4 == 0, so every block's row segment starts on a vec4.
layout(constant_id = 16) const bool YVEC4 = false;
// > 1: invocations come in KSPLIT parts, part z summing input channels
// [z * cper, (z + 1) * cper) into its own copy of the output (binding 5 is then the
// op's scratch, [KSPLIT][N][Cout][OH][OW]) with no epilogue; conv2d_split_sum.comp
// adds the parts. A small output of a long reduction then fills a big GPU.
layout(constant_id = 17) const uint KSPLIT = 1;
// Accumulators of a block row taken together through a step's fma chains (the row's
// last group may be smaller): each weight loaded feeds CG of them. Each accumulator's
// chain keeps its order, so every CG gives the same bits.
layout(constant_id = 18) const uint CG = 1;

const uint IR = (R - 1) * SH + KHB;  // input window rows per iteration
const uint IC = (C - 1) * SW + KW;   // input window columns

layout(std430, binding = 5) writeonly buffer Y_ { float Y[]; };
layout(std430, binding = 7) writeonly buffer Y4_ { vec4 Y4[]; };  // binding 5 seen as vec4
layout(push_constant) uniform Push {
    uint Cin, H, W, Cout, OH, OW;
    int pad_h, pad_w;
    uint bx, by, cb, lanes;  // column blocks, row blocks, channel blocks, total invocations
    float slope;
    int xq;                  // vec4 texels of x (XVEC4)
    uint part_lanes, cper;   // invocations and input channels per part (KSPLIT)
    uint total;              // outputs of one part, N * Cout * OH * OW
} p;

void main() {
    uint id = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * gl_WorkGroupSize.x +
              gl_LocalInvocationID.x;
    if (id >= p.lanes) return;
    uint z = 0;
    if (KSPLIT > 1u) {
        z = id / p.part_lanes;
        id -= z * p.part_lanes;
    }
    const uint ci_end = min(p.Cin, (z + 1) * p.cper);
    // Neighbouring invocations take neighbouring pixel blocks of the same channels:
    // they read the same weights and overlapping input windows.
    // The last block along each axis is moved back to end at the edge (the host
    // keeps R <= OH, C <= OW and, unless GUARD_CO, TM <= Cout), so every output an
    // invocation holds exists and the stores need no bounds checks. Overlapping
    // blocks write the same values twice.
    uint pb = id % (p.bx * p.by), rest = id / (p.bx * p.by);
    uint co0 = (rest % p.cb) * TM, n = rest / p.cb;
    if (!GUARD_CO) co0 = min(co0, p.Cout - TM);
    uint oy0 = min((pb / p.bx) * R, p.OH - R), ox0 = min((pb % p.bx) * C, p.OW - C);
    int iy0 = int(oy0 * SH) - p.pad_h, ix0 = int(ox0 * SW) - p.pad_w;

    // Zero padding by masking bits (an AND) rather than selecting (a blend).
    int colmask[IC];
    [[unroll]] for (uint c = 0; c < IC; ++c) colmask[c] = ix0 + int(c) >= 0 && ix0 + int(c) < int(p.W) ? -1 : 0;
    // Weight rows past Cout (a partial channel block) re-read the last valid one.
    uint last_co = p.Cout - 1, last_v4 = (p.Cin * KH * KW * p.Cout) / 4 - 1;

    float acc[TM * R * C];
    [[unroll]] for (uint i = 0; i < TM * R * C; ++i) acc[i] = 0.0;

    int xbase = int(n * p.Cin * p.H * p.W) + iy0 * int(p.W) + ix0;
    for (uint ci = z * p.cper; ci < ci_end; ++ci)
      [[unroll]] for (uint ky0 = 0; ky0 < KH; ky0 += KHB) {
        int rowmask[IR];
        [[unroll]] for (uint r = 0; r < IR; ++r) {
            int y = iy0 + int(ky0 + r);
            rowmask[r] = y >= 0 && y < int(p.H) ? -1 : 0;
        }
        float xin[IR * IC];
#ifdef LOAD_X4
        if (XVEC4) {
            // vec4s covering IC floats at offset XSHIFT, or at any offset
            const uint NF = XSHIFT < 4u ? (XSHIFT + IC + 3) / 4 : (IC + 6) / 4;
            [[unroll]] for (uint r = 0; r < IR; ++r) {
                int b = xbase + int((ci * p.H + ky0 + r) * p.W);  // flat index of the row's first tap
                int q0 = b >> 2, m = b & 3;
                float f[4 * NF];
                // Out-of-range vec4s (clamped) only ever feed taps that are masked below.
                [[unroll]] for (uint k = 0; k < NF; ++k) {
                    vec4 v = LOAD_X4(clamp(q0 + int(k), 0, p.xq - 1));
                    f[4 * k] = v.x, f[4 * k + 1] = v.y, f[4 * k + 2] = v.z, f[4 * k + 3] = v.w;
                }
                if (XSHIFT < 4u) {
                    [[unroll]] for (uint c = 0; c < IC; ++c)
                        xin[r * IC + c] = intBitsToFloat(floatBitsToInt(f[c + XSHIFT]) & (rowmask[r] & colmask[c]));
                } else {
                    // Shift by m in steps of 1 and 2: 2 * IC + 2 selects, not 3 * IC.
                    float g[IC + 2];
                    [[unroll]] for (uint c = 0; c < IC + 2; ++c) g[c] = (m & 1) != 0 ? f[c + 1] : f[c];
                    [[unroll]] for (uint c = 0; c < IC; ++c) {
                        float v = (m & 2) != 0 ? g[c + 2] : g[c];
                        xin[r * IC + c] = intBitsToFloat(floatBitsToInt(v) & (rowmask[r] & colmask[c]));
                    }
                }
            }
        } else
#endif
        [[unroll]] for (uint r = 0; r < IR; ++r)
            [[unroll]] for (uint c = 0; c < IC; ++c) {
                int mask = rowmask[r] & colmask[c];
                float v = LOAD_X(mask != 0 ? xbase + int((ci * p.H + ky0 + r) * p.W + c) : 0);
                xin[r * IC + c] = intBitsToFloat(floatBitsToInt(v) & mask);
            }
        vec4 w[KHB * KW * TM / 4];
        [[unroll]] for (uint t = 0; t < KHB * KW; ++t) {
            uint k = (ci * KH + ky0) * KW + t;  // (ci, ky, kx) flattened
            [[unroll]] for (uint i = 0; i < TM / 4; ++i) {
                if (WMODE == 2u) {
                    w[t * TM / 4 + i] = LOAD_W4(int(min((k * p.Cout + co0) / 4 + i, last_v4)));
                } else {
                    [[unroll]] for (uint j = 0; j < 4; ++j) {
                        uint co = min(co0 + 4 * i + j, last_co);
                        w[t * TM / 4 + i][j] = LOAD_W(int(WMODE == 0u ? co * p.Cin * KH * KW + k : k * p.Cout + co));
                    }
                }
            }
        }
        // CG neighbouring accumulators of a row at a time through all taps of the
        // step: they stay in registers for the whole chain.
        [[unroll]] for (uint m = 0; m < TM; ++m)
            [[unroll]] for (uint r = 0; r < R; ++r)
                [[unroll]] for (uint c0 = 0; c0 < C; c0 += CG) {
                    const uint G = min(CG, C - c0);
                    float s[CG];
                    [[unroll]] for (uint g = 0; g < G; ++g) s[g] = acc[(m * R + r) * C + c0 + g];
                    [[unroll]] for (uint ky = 0; ky < KHB; ++ky)
                        [[unroll]] for (uint kx = 0; kx < KW; ++kx) {
                            const float wv = w[(ky * KW + kx) * TM / 4 + m / 4][m % 4];
                            [[unroll]] for (uint g = 0; g < G; ++g)
                                s[g] = fma(wv, xin[(r * SH + ky) * IC + (c0 + g) * SW + kx], s[g]);
                        }
                    [[unroll]] for (uint g = 0; g < G; ++g) acc[(m * R + r) * C + c0 + g] = s[g];
                }
      }

    [[unroll]] for (uint m = 0; m < TM; ++m) {
        uint co = co0 + m;
        if (GUARD_CO && co >= p.Cout) break;
        float b = HAS_BIAS ? LOAD_BIAS(int(co)) : 0.0;
        [[unroll]] for (uint r = 0; r < R; ++r) {
            // The row segment's first output (in part z's copy when split).
            uint o = ((n * p.Cout + co) * p.OH + oy0 + r) * p.OW + ox0 + z * p.total;
#ifdef LOAD_RES4
            if (YVEC4) {
                [[unroll]] for (uint c = 0; c < C; c += 4) {
                    uint i = (m * R + r) * C + c;
                    vec4 v = vec4(acc[i], acc[i + 1], acc[i + 2], acc[i + 3]) + b;
                    if (HAS_RES) v += LOAD_RES4(int((o + c) / 4));
                    Y4[(o + c) / 4] = vec4(apply_act(v.x, ACT, p.slope), apply_act(v.y, ACT, p.slope),
                                           apply_act(v.z, ACT, p.slope), apply_act(v.w, ACT, p.slope));
                }
            } else
#endif
            [[unroll]] for (uint c = 0; c < C; ++c) {
                float v = acc[(m * R + r) * C + c] + b;
                if (HAS_RES) v += LOAD_RES(int(o + c));
                Y[o + c] = apply_act(v, ACT, p.slope);
            }
        }
    }
}
