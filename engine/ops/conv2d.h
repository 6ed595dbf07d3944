#pragma once
// conv2d's register tile (shaders/conv2d.comp) and its weight layouts.
#include <cstdint>

#include "engine/tensor.h"
#include "runtime/context.h"

namespace vtloc::ops {

// Weight layouts conv2d accepts (its "weight_layout" param).
enum ConvWeightLayout : uint32_t {
    kConvOIHW = 0,  // [Cout, Cin, KH, KW]: PyTorch's
    kConvIHWO = 1,  // [Cin, KH, KW, Cout]: output channels contiguous, read 4 at a time on the GPU
};

// PyTorch's [Cout, Cin, KH, KW] rearranged to [Cin, KH, KW, Cout].
HostTensor conv_weight_to_ihwo(const HostTensor& oihw);

struct ConvShape {
    int64_t n, cin, h, w, cout, kh, kw, sh, sw, oh, ow;
    int64_t pw = 0;  // left padding
};

// Per invocation: tm output channels x r rows x c columns; `local` invocations
// per workgroup.
struct ConvTiles {
    uint32_t tm, r, c, local;
    uint32_t kh_block;  // kernel rows per loop iteration: KH, or 1 for big kernels
    uint32_t x_shift;   // vec4 input rows: their offset mod 4 if the same for all blocks, else 4
    // > 1: the input channels are split into this many parts, each summed by its own
    // invocations into scratch, and a second pass adds the parts (then bias, residual,
    // activation): a small output of a long reduction (ResNet's layer3/4) then still
    // gives every compute unit of a big GPU workgroups.
    uint32_t ksplit = 1;
    // Accumulators of a block row taken together through a step's fma chains: each
    // weight loaded then feeds c_group of them. 4 for big convolutions where lavapipe's JIT
    // has 16 vector registers (AVX2: one accumulator at a time, each fma had both operands
    // to load), else 1.
    uint32_t c_group = 1;
    uint32_t accumulators() const { return tm * r * c; }
};

// Offset mod 4 of every input window row when it is the same for all blocks of
// width c (rows of a multiple of 4 floats, block origins a multiple of 4 apart),
// else 4.
uint32_t conv_window_shift(const ConvShape& s, uint32_t c);

// The tile with the lowest modelled run time on this device and shape, given
// whether weights (IHWO, Cout % 4 == 0) and input rows (numel % 4 == 0) are read
// as vec4s. On CPU devices (lavapipe) every fetch costs far more than an fma, so
// the model favours large register blocks that reuse each fetch, bounded by the
// unrolled shader's size. GPUs get a small block and whole subgroups, the block
// shrinking and then the reduction splitting (ksplit) until a dispatch offers
// rt::fill_workgroups(d) workgroups.
ConvTiles choose_conv_tiles(const rt::DeviceInfo& d, const ConvShape& s, bool vec4_weights, bool vec4_input);

}  // namespace vtloc::ops
