// Device faults: running out of device memory (a context memory budget), an
// allocation failing in the middle of a graph build, and VK_ERROR_DEVICE_LOST on
// submit (simulated). Each is one clear error; after it the context is either
// still usable (memory) or refuses further work by name (device lost), and the
// memory it held is given back (memory_in_use, counted per buffer).
#include <catch2/catch.hpp>
#include <cmath>

#include "base/error.h"
#include "engine/api/api_internal.h"
#include "engine/executor.h"
#include "engine/ops/build.h"
#include "runtime/context.h"
#include "tests/api_test_util.h"
#include "tests/harness.h"

using namespace vtloc;
using Catch::Contains;

namespace {

api::TactileImage frame(uint8_t v) { return api::TactileImage{120, 160, std::vector<uint8_t>(120 * 160 * 3, v)}; }

}  // namespace

TEST_CASE("a memory budget fails one allocation clearly, and the context stays usable and nothing leaks", "[faults]") {
    const std::string mug = test::source_path("examples/mug.glb");
    // What encoding an object and one touch hold on an unlimited context.
    uint64_t after_encode = 0, after_touch = 0;
    {
        api::Context ctx(test::validated());
        api::Model model(ctx, test::tiny_model());
        api::Object o = model.encode_object(mug);
        after_encode = ctx.memory_in_use();
        model.localize(o, frame(90));
        after_touch = ctx.memory_in_use();
    }
    REQUIRE(after_encode > 0);
    REQUIRE(after_touch > after_encode);

    api::ContextOptions opt = test::validated();
    opt.memory_budget = after_encode + (after_touch - after_encode) / 2;  // the object fits, the touch does not
    api::Context ctx(opt);
    api::Model model(ctx, test::tiny_model());
    api::Object o = model.encode_object(mug);
    CHECK(ctx.memory_in_use() == after_encode);
    CHECK_THAT(test::api_error([&] { model.localize(o, frame(90)); }),
               Contains("out of device memory") && Contains("over its budget"));
    CHECK(ctx.memory_in_use() == after_encode);  // the touch graph's buffers were all given back
    api::Object again = model.encode_object(mug);  // still usable for what fits
    CHECK(again.cloud().size() == o.cloud().size());
    CHECK(ctx.memory_in_use() == after_encode);
    test::require_no_validation(ctx);
}

TEST_CASE("an allocation failing in the middle of a graph build frees what was allocated before it", "[faults]") {
    rt::ContextOptions opt;
    opt.validation = 1;
    opt.memory_budget = 3u << 19;  // 1.5 MiB: the 1 MiB weight fits, then the 1 MiB activation arena does not
    rt::Context ctx(opt);
    WeightStore w;
    w.add("fc.weight", test::random_tensor({512, 512}, 1));
    Graph g;
    int x = g.input("x", {512, 512});
    g.output(ops::linear(g, x, g.weight("fc.weight", {512, 512}), -1), "y");
    CHECK_THROWS_WITH(GpuExecutor(ctx, g, w), Contains("out of device memory") && Contains("budget of 2 MiB"));
    CHECK(ctx.memory_in_use() == 0);
    CHECK(ctx.take_validation_messages().empty());
}

TEST_CASE("VK_ERROR_DEVICE_LOST on submit is one clear error, and the context then refuses work by name", "[faults]") {
    api::Context ctx(test::validated());
    api::Model model(ctx, test::tiny_model());
    api::Object o = model.encode_object(test::source_path("examples/mug.glb"));
    const api::TouchResult before = model.localize(o, frame(60));
    REQUIRE(std::isfinite(before.contact[0]));
    api::testing::simulate_device_loss(ctx);
    CHECK_THAT(test::api_error([&] { model.localize(o, frame(60)); }),
               Contains("VK_ERROR_DEVICE_LOST") && Contains("create a new context"));
    CHECK_THAT(test::api_error([&] { model.localize(o, frame(60)); }), Contains("was lost") && Contains("refuses"));
    CHECK_THAT(test::api_error([&] { model.encode_object(test::source_path("examples/mug.glb")); }),
               Contains("refuses further work"));
    // A new context on the same device works.
    api::Context fresh(test::validated());
    api::Model m2(fresh, test::tiny_model());
    const api::TouchResult r = m2.localize(m2.encode_object(test::source_path("examples/mug.glb")), frame(60));
    CHECK(r.contact == before.contact);
    test::require_no_validation(fresh);
}
