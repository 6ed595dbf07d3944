#pragma once
// Helpers shared by the op implementations in engine/ops/.
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "engine/op.h"
#include "runtime/context.h"
#include "runtime/pipeline.h"
#include "runtime/sequence.h"

namespace vtloc::ops {

// Activation codes; the same numbers as shaders/act.glsl.
enum Act : uint32_t { kActNone = 0, kActRelu = 1, kActLeaky = 2, kActTanh = 3, kActSigmoid = 4 };

// CPU mirror of apply_act in shaders/act.glsl (textbook formulas: the oracle).
float apply_act(float v, uint32_t act, float slope);

// Workgroup size for 1-D elementwise shaders: up to 256 invocations, a multiple
// of the subgroup size, within the device's limits.
uint32_t elementwise_local_size(const rt::DeviceInfo& d);
// The device has the subgroup operations the *_subgroup / *_wave shaders use
// (basic + shuffle) and a subgroup fits an elementwise workgroup.
bool has_subgroup_shuffles(const rt::DeviceInfo& d);
// The op may take its *_subgroup shader: the device has shuffles and the op's
// param "subgroup" (default 1) does not force the plain one.
bool shuffles_allowed(const GpuOpArgs& a);
// The op may read its inputs as uniform texel buffers (a gather on CPU drivers, where a
// storage read at each lane's own offset is a loop over the lanes): param "texel" (default
// 1) does not force storage buffers and every binding's texel count is within the device's
// maxTexelBufferElements.
bool texels_allowed(const GpuOpArgs& a, std::initializer_list<uint64_t> texels);
// Workgroup size for shaders with one invocation per output row (max_pool2d): the
// elementwise size, halved (in whole subgroups) until there are >= 16 groups. There
// are only hundreds to thousands of rows, and a full 256-wide group would leave CPU
// devices' threads (one workgroup each) idle.
uint32_t row_local_size(const rt::DeviceInfo& d, uint64_t rows);
// An elementwise pass over `items`: elementwise_local_size, halved (whole subgroups)
// while the dispatch would offer fewer than rt::fill_workgroups(d) workgroups.
uint32_t fill_local_size(const rt::DeviceInfo& d, uint64_t items);
// Workgroup size for n invocations along x (one row of the output, its rows along y):
// n in whole subgroups, at most the elementwise size (tactile_preprocess, concat).
uint32_t row_span_local_size(const rt::DeviceInfo& d, uint64_t n);
// Workgroup size of the *_subgroup shaders that spread rows over workgroups: 64
// invocations in whole subgroups (at least one), so a few hundred rows still
// reach every core of a CPU driver.
uint32_t subgroup_group_size(const rt::DeviceInfo& d);
// Answers (queries) each thread of such a shader serves per shuffled row: 4 on a CPU
// driver, where a shuffle cost more than the arithmetic it fed (lavapipe, chamfer's
// search: 2.6-2.9 -> 1.0-1.1 ms), 1 on a GPU, which shuffles in about one
// instruction and wants the threads.
uint32_t answers_per_shuffle(const rt::DeviceInfo& d);
// Lavapipe (llvmpipe) ends every loop of a shader once the loops of one
// invocation have taken 65535 back-edges in all (a limiter shared by all the
// shader's loops), silently. Shaders that put a long scan in one invocation (one
// subgroup per row) take it only while this bound on their loop iterations
// holds; the others spread the work over more invocations.
constexpr uint64_t kLoopIterationBudget = 60000;
// For a shader with no alternative: on a CPU device (where the limiter lives),
// refuses by name a dispatch whose invocations may loop more than the budget.
void check_loop_budget(const rt::DeviceInfo& d, uint64_t iterations, const std::string& what);
// retrieve.cpp: whether retrieve's one-subgroup shader applies to the op `a`
// (inputs contact, candidates, cloud[, symmetry]; outputs index, score, heat-map)
// after `loops_before` loop iterations of the same invocation (ilu_retrieve's ILU),
// and its bindings but the contact: cloud, candidates, index, symmetry slot,
// heat-map, candidates as texels, score (retrieve_subgroup.comp 0-6).
bool retrieve_fits_subgroup(const GpuOpArgs& a, uint64_t loops_before);
std::vector<rt::Binding> retrieve_subgroup_bindings(const GpuOpArgs& a);
constexpr uint32_t kRetrieveSubgroupTexels = 0x21u;  // bindings 0 and 5 of those
// Workgroup count for a grid-stride loop over n items.
uint32_t grid_groups(uint64_t n, uint32_t local_size, const rt::DeviceInfo& d);

const rt::Pipeline& pipeline(rt::Context& ctx, const char* shader, uint32_t bindings,
                             uint32_t push_bytes, std::vector<uint32_t> spec);

// Shaders index with 32-bit integers; larger tensors are rejected clearly.
uint32_t to_u32(int64_t v, const char* what);
void expect_input_count(const std::vector<TensorDesc>& in, size_t lo, size_t hi);
// Throws unless every input is fp32 (most ops).
void expect_f32(const std::vector<TensorDesc>& in);

}  // namespace vtloc::ops
