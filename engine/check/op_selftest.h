#pragma once
// The built-in op self-test behind `vtloc check --ops` and api::check_ops: every
// registered op on the device against its CPU reference, at the odd shapes and
// variants the op tests use (texel and storage-buffer paths, the tile shapes
// the device's limits pick), with no Catch2, golden file or Python. Cases live
// in op_cases_*.cpp; an op of the registry with no case fails the self-test.
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "engine/check/compare.h"
#include "engine/executor.h"

namespace vtloc::rt {
class Context;
struct DeviceInfo;
}  // namespace vtloc::rt

namespace vtloc::check {

// One graph (usually one node) and its inputs; every output is compared.
struct OpCase {
    std::string op;       // the registry op this case covers
    std::string variant;  // what is special about it ("odd shape", "storage-buffer path", ...)
    Graph g;
    WeightStore w;
    TensorMap in;
    Tolerance tol = kNodeTolerance;

    OpCase(std::string op_name, std::string variant_text) : op(std::move(op_name)), variant(std::move(variant_text)) {}
    int input(const std::string& name, HostTensor t);
    int weight(const std::string& name, HostTensor t);
    void output(int value, const std::string& name) { g.output(value, name); }
};

// Seeded uniform values in [lo, hi) (std::mt19937; fixed for a seed).
HostTensor random_tensor(const Shape& shape, uint32_t seed, float lo = -1.0f, float hi = 1.0f);
// A random unit vector in out[0..2] and a unit vector orthogonal to it in out[3..5]
// (six normal draws from rng): a normal and its tangent (the multi-touch filter's cases).
void random_unit_pair(std::mt19937& rng, float* out);
// A random neighbour table for field_slack [S, KN, 3]: 0..KN neighbours a sample (then -1
// rows), squared distances in [0, 10), spin offsets in 0..NS-1.
HostTensor random_slack_neighbours(int64_t S, int64_t KN, int64_t NS, uint32_t seed);

// Balls in SPEC 2's layout (real slots, then the first index again) of very
// different lengths in one subgroup, [S, NS] indices into P points: in each run of 8
// balls one is full, one 40 rows long, the rest 1-7 rows; balls 32 on are 20 rows
// each; ball 11 repeats its first index in slot 5, real rows after it.
HostTensor uneven_balls(int64_t S, int64_t NS, int64_t P);

// The case lists, by op family.
std::vector<OpCase> dense_cases(const rt::DeviceInfo& d);  // linear, binary, activations, concat, flatten
std::vector<OpCase> image_cases(const rt::DeviceInfo& d);  // conv2d, pools, tactile_preprocess
std::vector<OpCase> point_cases(const rt::DeviceInfo& d);  // fps, ball_query, grouping, cloud_normalize
std::vector<OpCase> head_cases(const rt::DeviceInfo& d);   // GMA, chamfer, ILU, top-K, heat-map
std::vector<OpCase> track_cases(const rt::DeviceInfo& d);  // the multi-touch filter's ops
std::vector<OpCase> gel_cases(const rt::DeviceInfo& d);    // the gel's shape from a frame
std::vector<OpCase> codebook_cases(const rt::DeviceInfo& d);  // render-and-compare

struct OpCaseResult {
    std::string op, variant;
    std::vector<std::string> dispatches;  // shader, spec constants (tile shape), workgroups
    Comparison cmp;
    Tolerance tol;
    std::string error;  // recording or the reference failed
    double ms = 0;      // record + GPU run + reference
    bool ok() const { return cmp.ok && error.empty(); }
};

struct OpsCheck {
    std::vector<OpCaseResult> cases;
    std::vector<std::string> uncovered;  // registered ops with no case: a failure
    double ms = 0;
    bool ok() const;
};

// Runs every case (or those whose op contains `filter`); progress(i, n, result)
// after each case when given.
OpsCheck check_ops(rt::Context& ctx, const std::string& filter = "",
                   const std::function<void(size_t, size_t, const OpCaseResult&)>& progress = {});

}  // namespace vtloc::check
