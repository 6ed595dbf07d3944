#pragma once
// The ILU head's math in double, shared by the CPU references of ilu (fused)
// and ilu_step (one iteration per dispatch). Inputs in the ops' order:
// 0 F^t [1, C] (ilu: [B, C], B touches), 1 F^p [1, C], 2 N (I32 [1]), 3..8 convz/convr/convq weight
// [C, 3C] and bias [C], 9 head.0.weight [H, C], 10 head.0.bias, 11
// head.2.weight [3, H], 12 head.2.bias.
#include <vector>

#include "engine/op.h"
#include "engine/tensor.h"
#include "runtime/sequence.h"

namespace vtloc::ops::ilu_math {

// Checks inputs 0..12 (types and shapes) and returns their 13 descriptors' C.
// `batch`: F^t may hold B >= 1 rows (one GRU state each, all with the one F^p).
int64_t check_inputs(const std::vector<TensorDesc>& in, bool batch = false);

struct State {
    std::vector<double> h;   // [C]
    std::vector<double> gx;  // [3C]: x half of the z, r, q gates plus their biases
    double c[3] = {0, 0, 0};
};

// h_0 = tanh(F^t), c = 0, gx from x = [F^p, ReLU(F^t)], for F^t's row `row`.
State init(const std::vector<const HostTensor*>& in, int64_t row = 0);
// One GRU update of h, then c += head(h).
void iterate(const std::vector<const HostTensor*>& in, State& s);

// The shaders' spec constants (workgroup size L, C, H, lanes per row G); throws
// when h and the gates do not fit the device's shared memory. Param "lanes"
// overrides the default of 8 lanes per row (tests cover both shader paths).
// subgroup: the row sums by subgroup shuffles (the *_subgroup shaders) where the
// device has them, G divides its subgroup size and L is whole subgroups; param
// "subgroup" = 0 keeps the shared-memory sums (tests run both).
// wave: the register-resident variant (shaders/ilu_wave.comp) where the device
// has subgroup shuffles, C and H are multiples of 4 and the weights fit texel
// buffers: a workgroup of one subgroup (wave_L invocations), no barriers, on CPU
// devices only (wave_by_default). Param "wave" = 0 turns it off; a value >= 2 asks
// for that workgroup size instead on any device (tests use twice the subgroup size
// to run its shared-memory path).
struct Launch {
    uint32_t L, C, H, G;
    bool subgroup;
    bool wave = false;
    uint32_t wave_L = 0, RB = 0, HB = 0;
    uint64_t wave_loops = 0;  // the wave shader's loop iterations in one invocation (kLoopIterationBudget)
};
Launch launch(const GpuOpArgs& a);
// Whether param wave = 1 (the default) takes the register-resident shader. On
// lavapipe it runs the lite head 9x faster than the shared-memory one (one subgroup
// is one SIMD stream there); on an NVIDIA H200 the shared-memory one, 256
// invocations, ran the paper's ILU node (C 128, N 16) in 0.27 ms against 0.66 ms
// and the lite one's (C 64) in 0.09 against 0.17 ms (vtloc-bench, "ILU node's
// shaders", 2026-11-30): one subgroup leaves a GPU's load latency unhidden.
bool wave_by_default(const rt::DeviceInfo& d);
// The wave shader's (ilu_wave.glsl) 15 bindings: the inputs, then c and contact;
// gate and head.0 weights as vec4 texels, head.2 as floats (kWaveTexels).
std::vector<rt::Binding> wave_bindings(const GpuOpArgs& a);
constexpr uint32_t kWaveTexels = 0xAA8u;  // bindings 3, 5, 7, 9, 11

}  // namespace vtloc::ops::ilu_math
