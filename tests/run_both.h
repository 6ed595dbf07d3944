#pragma once
// Runs a graph on the CPU reference and on the GPU (validation on) and returns
// both, for tests that compare integer outputs exactly (test::require_close
// compares fp32 and would not see a wrong index).
#include <catch2/catch.hpp>

#include "tests/harness.h"

namespace vtloc::test {

struct BothRuns {
    TensorMap cpu, gpu;
};

inline BothRuns run_both(const Graph& g, const WeightStore& w, const TensorMap& inputs) {
    BothRuns r{run_cpu(g, w, inputs), {}};
    GpuExecutor exec(gpu(), g, w);
    r.gpu = exec.run(inputs);
    require_no_validation_messages();
    return r;
}

inline void require_same_ints(const HostTensor& got, const HostTensor& want, const std::string& what) {
    INFO(what);
    REQUIRE(got.type == ElemType::I32);
    REQUIRE(want.type == ElemType::I32);
    CHECK(got.ints() == want.ints());
}

}  // namespace vtloc::test
