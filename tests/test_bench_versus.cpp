// bench::engine_over_pytorch: the engine/PyTorch ratios vtloc-bench --vs-pytorch
// reports, on reports written by hand.
#include <catch2/catch.hpp>

#include "bench/versus.h"

using namespace vtloc;
using nlohmann::json;

namespace {

json stat(double median, double min) { return json{{"median", median}, {"min", min}, {"n", 1}}; }

// An engine report whose retrieval runs in the head's dispatch, its share `epilogue_ms`.
json engine(double epilogue_ms) {
    return json{{"end_to_end_ms", stat(10.0, 8.0)},
                {"stages_ms", {{"preprocess", stat(0.2, 0.2)}, {"tactile", stat(4.0, 3.0)}, {"point", stat(3.0, 2.5)},
                               {"gma", stat(0.6, 0.5)}, {"head", stat(0.1, 0.1)}}},
                {"retrieval_split", {{"fused_head_ms", 0.1 + epilogue_ms}, {"head_alone_ms", 0.1}, {"epilogue_ms", epilogue_ms}}}};
}

json torch() {
    return json{{"end_to_end_ms", stat(20.0, 10.0)},
                {"stages_ms", {{"preprocess", stat(0.1, 0.1)}, {"tactile", stat(2.0, 2.0)}, {"point", stat(6.0, 6.0)},
                               {"heads", stat(1.4, 1.4)}, {"retrieval", stat(0.5, 0.5)}}}};
}

}  // namespace

TEST_CASE("engine over PyTorch: each stage's ratio, retrieval taken out of the head", "[bench]") {
    const json r = bench::engine_over_pytorch(engine(0.04), torch());
    CHECK(r.at("end_to_end").get<double>() == Approx(0.5));
    CHECK(r.at("end_to_end_fastest").get<double>() == Approx(0.8));
    CHECK(r.at("stage tactile").get<double>() == Approx(2.0));
    CHECK(r.at("stage point").get<double>() == Approx(0.5));
    CHECK(r.at("stage retrieval").get<double>() == Approx(0.04 / 0.5));
    CHECK(r.at("stage gma + head").get<double>() == Approx((0.6 + 0.1 - 0.04) / 1.4));
}

TEST_CASE("engine over PyTorch: a noisy retrieval split stays within the head", "[bench]") {
    // The split's runs are not the stage medians' runs: noise can make the
    // retrieval's share negative (no retrieval ratio) or larger than the whole head
    // (then it is the head); GMA + head keeps a ratio either way.
    const json below = bench::engine_over_pytorch(engine(-0.02), torch());
    CHECK_FALSE(below.contains("stage retrieval"));
    CHECK(below.at("stage gma + head").get<double>() == Approx(0.7 / 1.4));
    const json above = bench::engine_over_pytorch(engine(0.9), torch());  // head 0.1, GMA 0.6
    CHECK(above.at("stage retrieval").get<double>() == Approx(0.1 / 0.5));
    REQUIRE(above.contains("stage gma + head"));
    CHECK(above.at("stage gma + head").get<double>() == Approx(0.6 / 1.4));
}
