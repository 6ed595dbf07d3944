// Device profiles (runtime/device_profile.h) and planning on them: the shipped
// profiles read, a written profile reads back the same, a bad one names its file
// and field, and a plan-only context records what the profile's GPU would get
// (checked against its limits) without running anything.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include "base/error.h"
#include "engine/executor.h"
#include "engine/model/vtloc_runner.h"
#include "engine/ops/build.h"
#include "runtime/device_profile.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

std::string profile_path(const std::string& name) { return std::string(VTLOC_SOURCE_DIR) + "/bench/device_profiles/" + name; }

std::string read_text(const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

}  // namespace

TEST_CASE("the shipped device profiles read, and a written profile reads back the same", "[runtime][profile]") {
    for (const char* name : {"nvidia-h200.json", "jetson-orin-nano.json", "mali-4core-conservative.json"}) {
        INFO(name);
        const rt::DeviceInfo d = rt::read_device_profile(profile_path(name));
        CHECK(d.type != VK_PHYSICAL_DEVICE_TYPE_CPU);
        CHECK(d.compute_units > 0);
        CHECK(rt::fill_workgroups(d) == 4ull * d.compute_units);
        const rt::DeviceInfo back = rt::parse_device_profile(rt::device_profile_json(d), "written");
        CHECK(back.name == d.name);
        CHECK(back.subgroup_size == d.subgroup_size);
        CHECK(back.subgroup_ops == d.subgroup_ops);
        CHECK(back.max_workgroup_count == d.max_workgroup_count);
        CHECK(back.max_texel_elements == d.max_texel_elements);
        CHECK(back.compute_units == d.compute_units);
    }
    // This machine's device, written and read back (what `vtloc devices --save-profile` does).
    const rt::DeviceInfo& real = test::gpu().info();
    const rt::DeviceInfo back = rt::parse_device_profile(rt::device_profile_json(real), "this device");
    CHECK(back.max_shared_memory == real.max_shared_memory);
    CHECK(back.max_storage_buffer_range == real.max_storage_buffer_range);
    CHECK(back.tensor_alignment() == real.tensor_alignment());
}

TEST_CASE("a bad device profile names its file and field", "[runtime][profile]") {
    const std::string good = read_text(profile_path("nvidia-h200.json"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile("{", "p.json"), Catch::Contains("p.json") && Catch::Contains("invalid JSON"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile("{}", "p.json"), Catch::Contains("vtloc-device-profile/1"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile("{\"format\": 64}", "p.json"), Catch::Contains("vtloc-device-profile/1"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile("[1]", "p.json"), Catch::Contains("vtloc-device-profile/1"));
    auto edited = [&](const std::string& from, const std::string& to) {
        std::string s = good;
        const size_t at = s.find(from);
        REQUIRE(at != std::string::npos);
        return s.replace(at, from.size(), to);
    };
    REQUIRE_THROWS_WITH(rt::parse_device_profile(edited("\"subgroup_size\": 32", "\"subgroup_size\": 24"), "p.json"),
                        Catch::Contains("p.json") && Catch::Contains("'subgroup_size'") && Catch::Contains("power of two"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile(edited("\"max_invocations\": 1024", "\"max_invocations\": -3"), "p.json"),
                        Catch::Contains("'max_invocations'"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile(edited("\"max_invocations\": 1024", "\"max_invocation\": 1024"), "p.json"),
                        Catch::Contains("'max_invocations' is missing"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile(edited("\"discrete GPU\"", "\"gpu\""), "p.json"), Catch::Contains("'type'"));
    REQUIRE_THROWS_WITH(rt::parse_device_profile(edited("\"quad\"", "\"quads\""), "p.json"),
                        Catch::Contains("'subgroup_ops'") && Catch::Contains("quads"));
    REQUIRE_THROWS_WITH(rt::read_device_profile("/nonexistent/p.json"), Catch::Contains("/nonexistent/p.json"));
}

TEST_CASE("a plan-only context records a profile's dispatches and runs none", "[runtime][profile]") {
    rt::ContextOptions o;
    o.validation = 1;
    o.plan_for = rt::read_device_profile(profile_path("nvidia-h200.json"));
    rt::Context plan(o);
    CHECK(plan.plan_only());
    CHECK(plan.info().compute_units == 132);
    CHECK(plan.info().subgroup_size == 32);
    // ResNet-18's layer3 and layer4 convolutions at 224: small outputs of long reductions.
    Graph g;
    int x = g.input("x", {1, 256, 14, 14});
    const int w3 = g.weight("w3", {256, 256, 3, 3}), w4 = g.weight("w4", {512, 256, 3, 3});
    x = ops::conv2d(g, x, w3, -1, -1, ops::Conv2d{1, 1, 1, 1, ops::kConvOIHW, ops::kActRelu}, "layer3");
    g.output(ops::conv2d(g, x, w4, -1, -1, ops::Conv2d{2, 2, 1, 1, ops::kConvOIHW, ops::kActRelu}, "layer4"), "y");
    WeightStore ws;
    ws.add("w3", HostTensor({256, 256, 3, 3}));
    ws.add("w4", HostTensor({512, 256, 3, 3}));
    GpuExecutor ex(plan, g, ws);
    const auto& log = ex.sequence().dispatch_log();
    REQUIRE(log.size() == 4);  // each convolution in parts, then their sum
    for (const auto& r : log) {
        INFO(r.node << " " << r.shader << " " << r.groups[0] << "x" << r.groups[1]);
        CHECK(uint64_t(r.groups[0]) * r.groups[1] * r.groups[2] >= 132);  // every SM has work
        CHECK(r.spec[0] % 32 == 0);  // whole subgroups of the profile's size
    }
    CHECK(ex.memory_plan().scratch_bytes > 0);
    REQUIRE_THROWS_WITH(ex.run({{"x", HostTensor({1, 256, 14, 14})}}),
                        Catch::Contains("NVIDIA H200") && Catch::Contains("never runs them"));
    CHECK(plan.take_validation_messages().empty());
}

TEST_CASE("on a plan-only H200 the point MLPs and GMA's decoder give every SM work", "[runtime][profile]") {
    // Layers of the paper's model that offered 16-64 workgroups before their tiles
    // shrank on GPUs: SA3's last layer (a max over 128 rows), the point head's one row,
    // a GMA decoder layer of 256 rows.
    rt::ContextOptions o;
    o.validation = 1;
    o.plan_for = rt::read_device_profile(profile_path("nvidia-h200.json"));
    rt::Context plan(o);
    Graph g;
    const int x = g.input("x", {512, 128}), row = g.input("row", {1, 1024}), pts = g.input("pts", {256, 128});
    ops::GroupLinear sa3{ops::GroupLinear::Input::Rows, 0, true, 128, ops::kActRelu};
    g.output(ops::group_linear(g, {x, g.weight("w", {512, 1024}), g.weight("b", {1024})}, sa3, "sa3.max"), "sa3");
    g.output(ops::linear(g, row, g.weight("wr", {512, 1024}), -1, ops::kActRelu, 0.01, "point.mlp"), "head");
    g.output(ops::linear(g, pts, g.weight("wg", {64, 128}), -1, ops::kActLeaky, 0.01, "gma.decoder"), "gma");
    WeightStore ws;
    ws.add("w", HostTensor({512, 1024}));
    ws.add("b", HostTensor({1024}));
    ws.add("wr", HostTensor({512, 1024}));
    ws.add("wg", HostTensor({64, 128}));
    GpuExecutor ex(plan, g, ws);
    const auto& log = ex.sequence().dispatch_log();
    REQUIRE(log.size() == 3);
    for (const auto& r : log) {
        INFO(r.node << " " << r.shader << " " << r.groups[0] << "x" << r.groups[1] << " of " << r.spec[0]);
        CHECK(uint64_t(r.groups[0]) * r.groups[1] * r.groups[2] >= 132);
        CHECK(r.spec[0] % 32 == 0);
    }
    CHECK(plan.take_validation_messages().empty());
}

TEST_CASE("on a plan-only H200 FPS takes 2 points a thread and the point encoder's rows go channel-major",
          "[runtime][profile]") {
    // Both choices measured on an H200 (engine/ops/fps.cpp, point_major_rows_on);
    // a CPU driver keeps its own (lavapipe: one subgroup of 32 points a lane, point-major rows).
    rt::ContextOptions o;
    o.validation = 1;
    o.plan_for = rt::read_device_profile(profile_path("nvidia-h200.json"));
    rt::Context plan(o);
    for (auto [N, S, want] : {std::tuple<int64_t, int64_t, uint32_t>{1024, 512, 512}, {512, 128, 256}, {100, 50, 64},
                              {16384, 512, 1024}}) {
        INFO(N << " -> " << S << " points");
        Graph g;
        g.output(ops::fps(g, g.input("x", {N, 3}), S, "fps")[0], "i");
        GpuExecutor ex(plan, g, WeightStore{});
        REQUIRE(ex.sequence().dispatch_log().size() == 1);
        CHECK(ex.sequence().dispatch_log()[0].shader == "fps_subgroup");
        CHECK(ex.sequence().dispatch_log()[0].spec.at(0) == want);
        if (test::gpu().info().type == VK_PHYSICAL_DEVICE_TYPE_CPU && N <= 1024) {
            GpuExecutor here(test::gpu(), g, WeightStore{});
            CHECK(here.sequence().dispatch_log().at(0).spec.at(0) < want);
        }
    }
    const WeightStore tiny = WeightStore::load(test::tiny_model());
    auto point_major_layers = [&](rt::Context& ctx) {
        VtlocRunner runner(tiny, &ctx);
        const HostTensor cloud = test::random_tensor({300, runner.config().point.use_normals ? 6 : 3}, 7);
        const HostTensor image(Shape{120, 160, 3}, ElemType::I32);
        const Graph g = runner.prepare_once(image, cloud, nullptr).graph;
        int layers = 0, point_major = 0;
        for (const Node& n : g.nodes())
            if (n.op == "group_linear") ++layers, point_major += n.params.get("point_major", 0) != 0;
        REQUIRE(layers > 0);
        return point_major;
    };
    CHECK(point_major_layers(plan) == 0);
    if (test::gpu().info().type == VK_PHYSICAL_DEVICE_TYPE_CPU) CHECK(point_major_layers(test::gpu()) > 0);
    CHECK(plan.take_validation_messages().empty());
}

TEST_CASE("a context held to a smaller texel limit takes the storage-buffer paths and gives the same bits", "[runtime][profile]") {
    // ContextOptions::max_texel_elements (VTLOC_MAX_TEXEL_ELEMENTS): the device's limit, lowered.
    rt::ContextOptions o;
    o.validation = 1;
    o.max_texel_elements = 70000;
    rt::Context small(o);
    const uint32_t own = test::gpu().info().max_texel_elements;
    if (!std::getenv("VTLOC_MAX_TEXEL_ELEMENTS")) CHECK(small.info().max_texel_elements == std::min<uint32_t>(own, 70000));
    o.max_texel_elements = 4096;
    CHECK_THROWS_WITH(rt::Context(o), Catch::Contains("below Vulkan's minimum, 65536"));
    // An op whose input passes the lowered limit runs its storage-buffer shader there, the
    // same numbers as the texel one on the full limit (log_softmax: 80,000 scores).
    Graph g;
    const HostTensor score = test::random_tensor({80000}, 17, -30.0f, 5.0f);
    g.output(ops::log_softmax(g, g.input("score", {80000}), "sm")[0], "log");
    WeightStore w;
    const TensorMap in{{"score", score}};
    GpuExecutor full(test::gpu(), g, w, std::make_shared<ResidentWeights>(test::gpu()));
    GpuExecutor held(small, g, w, std::make_shared<ResidentWeights>(small));
    CHECK(held.run(in).at("log").data == full.run(in).at("log").data);
    auto shaders = [](const GpuExecutor& e) {
        std::set<std::string> s;
        for (const rt::Sequence::DispatchRecord& d : e.sequence().dispatch_log()) s.insert(d.shader);
        return s;
    };
    // (Unless the tests themselves run held to the limit: VTLOC_MAX_TEXEL_ELEMENTS.)
    if (test::gpu().info().max_texel_elements >= 80000) CHECK(shaders(full).count("log_softmax") == 1);
    CHECK(shaders(held).count("log_softmax_ssbo") == 1);
    CHECK(small.take_validation_messages().empty());
}
