#pragma once
// GMA (SPEC 2): [F^t, F^p] -> W^d einsum + LeakyReLU -> per-point decoder ->
// pseudo-cloud P^d [N^d, 6]. W^d (2C x N^d x C^d, 64 MiB in the paper config) may
// exceed what one shader binding can hold on some devices, so it can be split
// into row chunks `gma.weight#0`, `gma.weight#1`, ... at load time.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/model/model_config.h"
#include "engine/weights.h"

namespace vtloc {

// Vulkan guarantees maxStorageBufferRange >= 2^27 on every device.
constexpr uint64_t kPortableBindingBytes = 1ull << 27;

// Rows per chunk so that each chunk of `row_bytes`-sized rows fits `max_bytes`
// (the last chunk takes the remainder). Throws when one row alone is too big.
std::vector<int64_t> plan_row_chunks(int64_t rows, uint64_t row_bytes, uint64_t max_bytes);

// Splits weight `name` ([K, ...]) along its first axis into `name#0`, `name#1`,
// ... of at most `max_bytes` each, added to `w` (the original stays). A weight
// that fits is not copied. Returns the names to bind, in row order.
std::vector<std::string> split_weight_rows(WeightStore& w, const std::string& name, uint64_t max_bytes);

// The chunk names split_weight_rows made for `name` (or {name} if it was not split).
std::vector<std::string> weight_row_chunks(const WeightStore& w, const std::string& name);

// P^d from F^t and F^p ([1, C] each): disentangle (with the chunks above),
// decoder MLP gma.decoder.{0,2,..} with LeakyReLU(0.01), then xyz = tanh,
// unit normals. Returns P^d as [1, N^d, 6] (the batch axis of F^t kept).
int build_gma(Graph& g, const WeightStore& w, const ModelConfig& config, int ft, int fp);

}  // namespace vtloc
