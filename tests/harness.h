#pragma once
// Shared test helpers: one validated Vulkan context per process, seeded
// random tensors, and fp32 comparison with a stated tolerance.
#include <string>

#include "engine/executor.h"
#include "engine/graph.h"
#include "engine/ops/build.h"
#include "engine/tensor.h"
#include "engine/weights.h"
#include "runtime/context.h"

namespace vtloc::test {

// The process-wide context, created on first use with the Khronos validation layer on.
rt::Context& gpu();
bool gpu_created();
// Destroys the shared context. main() calls it before returning: g_ctx's
// destructor was registered before main, so exit() would run it after the
// handlers the driver registered when it was loaded, and on NVIDIA's driver
// that crashed.
void release_gpu();

// Whether tests force group_linear's big-layer tiles (GroupLinear::Tile::Big*): only
// CPU devices take them. A GPU never runs them, and NVIDIA's compiler spent minutes
// on their unrolled shaders (an H200, 2026-11-30: tests stalled past 290 s).
bool big_tiles_apply();

// Whether a group_linear variant's shader uses subgroup operations (point_mlp_shfl:
// texel buffers, shuffled weights). The README's subgroup-4 run sweeps these variants
// only ([subgroup_sweep]); a test checks the claim against each shader's SPIR-V.
inline bool subgroup_shader_variant(ops::BufferPath path, ops::GroupLinear::Weights w) {
    return path == ops::BufferPath::Texel && w == ops::GroupLinear::Weights::Shuffle;
}

// Whether a point-MLP sweep runs a tile on a buffer path: a CPU device reads its layers
// as texel buffers, so the big-layer tiles on storage buffers (the slowest pipelines to
// compile) run only where a sweep asks (the long suite: big_on_storage).
inline bool sweep_takes_tile(ops::BufferPath path, ops::GroupLinear::Tile tile, bool big_on_storage) {
    return tile == ops::GroupLinear::Tile::Auto || path != ops::BufferPath::Storage || big_on_storage;
}

// Fails the current test (CHECK) if the validation layer said anything since the last call.
void require_no_validation_messages();

HostTensor random_tensor(const Shape& shape, uint32_t seed, float lo = -1.0f, float hi = 1.0f);
// A 2-D tensor [R, C] as [C, R] (channel-major rows as point-major and back).
HostTensor transposed(const HostTensor& t);

// fp32 default: |got - want| <= abs + rel * |want| elementwise.
struct Tolerance {
    double abs = 1e-4;
    double rel = 1e-4;
};
void require_close(const HostTensor& got, const HostTensor& want, Tolerance tol, const std::string& what);

// Runs g on the GPU (validation on) and with the CPU references; every output must agree.
TensorMap run_gpu_and_compare(const Graph& g, const WeightStore& w, const TensorMap& inputs,
                              Tolerance tol = {});

std::string temp_path(const std::string& name);

}  // namespace vtloc::test
