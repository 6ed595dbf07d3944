// The Vulkan runtime: device choice, embedded shaders, pipeline cache,
// automatic barriers (only on hazards) and timestamps.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "base/error.h"
#include "engine/ops/build.h"
#include "engine/ops/common.h"
#include "runtime/spirv_reflect.h"
#include "shaders/shader_registry.h"
#include "tests/harness.h"

using namespace vtloc;

TEST_CASE("the device reports the limits shaders depend on", "[runtime]") {
    const rt::DeviceInfo& d = test::gpu().info();
    INFO(d.name << " subgroup " << d.subgroup_size << " shared " << d.max_shared_memory);
    CHECK(test::gpu().validation_enabled());
    CHECK(d.subgroup_size >= 1);
    CHECK((d.subgroup_size & (d.subgroup_size - 1)) == 0);
    CHECK(d.max_shared_memory >= 16384);  // Vulkan's guaranteed minimum
    CHECK(d.max_invocations >= 128);
    CHECK(d.max_storage_buffer_range >= (1u << 27));
    CHECK(d.api_version >= VK_API_VERSION_1_1);
    CHECK(d.max_storage_buffers >= 4);  // Vulkan's guaranteed minimum; pipelines check their own needs
    CHECK(d.max_uniform_range >= 16384);  // Vulkan's guaranteed minimum
    CHECK(d.tensor_alignment() % d.uniform_offset_alignment == 0);
    // A CPU device names the host's vector registers (group_linear's big tile follows
    // them); on x86 the answer must agree with the kernel's CPU flags. GPUs say 0.
    if (d.type != VK_PHYSICAL_DEVICE_TYPE_CPU) {
        CHECK(d.host_vector_registers == 0);
    } else {
        CHECK((d.host_vector_registers == 16 || d.host_vector_registers == 32));
#if defined(__x86_64__)
        std::ifstream cpuinfo("/proc/cpuinfo");
        std::string line;
        bool vl = false, seen = false;
        while (!seen && std::getline(cpuinfo, line))
            if (line.rfind("flags", 0) == 0) seen = true, vl = (line + " ").find(" avx512vl ") != std::string::npos;
        // Unless the environment holds Mesa's JIT below AVX-512 (next test).
        const bool held = rt::mesa_jit_below_avx512();
        if (seen && !held)
            CHECK(d.host_vector_registers == (vl ? 32u : 16u));
        else if (seen)
            CHECK(d.host_vector_registers == 16u);
        else
            WARN("no flags line in /proc/cpuinfo: host_vector_registers not checked against the CPU's flags");
#endif
    }
}

TEST_CASE("host_vector_registers follows Mesa's CPU-caps override as lavapipe's JIT does", "[runtime]") {
#if defined(__x86_64__)
    // Mesa (util/u_cpu_detect.c) clears AVX-512 for each level it knows and
    // ignores other values; the same must hold here, or a held-back JIT would get
    // the 32-register tile.
    struct Saved {
        std::string name;
        bool had;
        std::string value;
    };
    std::vector<Saved> saved;
    for (const char* n : {"GALLIUM_OVERRIDE_CPU_CAPS", "GALLIUM_NOSSE"}) {
        const char* v = std::getenv(n);
        saved.push_back({n, v != nullptr, v ? v : ""});
        unsetenv(n);
    }
    const uint32_t free_jit = rt::host_vector_registers();
    for (const char* level : {"nosse", "sse", "sse2", "sse3", "ssse3", "sse4.1", "avx"}) {
        setenv("GALLIUM_OVERRIDE_CPU_CAPS", level, 1);
        INFO(level);
        CHECK(rt::host_vector_registers() == 16u);
    }
    for (const char* other : {"", "avx2", "bogus"}) {
        setenv("GALLIUM_OVERRIDE_CPU_CAPS", other, 1);
        INFO("'" << other << "'");
        CHECK(rt::host_vector_registers() == free_jit);
    }
    unsetenv("GALLIUM_OVERRIDE_CPU_CAPS");
    for (const char* yes : {"1", "y", "Yes", "TRUE", "t"}) {
        setenv("GALLIUM_NOSSE", yes, 1);
        INFO("GALLIUM_NOSSE=" << yes);
        CHECK(rt::mesa_jit_below_avx512());
        CHECK(rt::host_vector_registers() == 16u);
    }
    for (const char* no : {"0", "no", "false", "maybe"}) {
        setenv("GALLIUM_NOSSE", no, 1);
        INFO("GALLIUM_NOSSE=" << no);
        CHECK(!rt::mesa_jit_below_avx512());
        CHECK(rt::host_vector_registers() == free_jit);
    }
    for (const Saved& s : saved) {
        if (s.had) setenv(s.name.c_str(), s.value.c_str(), 1);
        else unsetenv(s.name.c_str());
    }
#else
    CHECK((rt::host_vector_registers() == 16u || rt::host_vector_registers() == 32u));
#endif
}

TEST_CASE("a uniform binding beyond maxUniformBufferRange or misaligned is refused by name", "[runtime]") {
    rt::Context& ctx = test::gpu();
    const uint64_t big = ctx.info().max_uniform_range + 16;
    rt::Buffer buf(ctx, big + 4096, rt::MemoryKind::Device);
    const rt::Pipeline& p = ctx.pipelines().get(
        rt::PipelineDesc{"point_mlp_ubo", 12, 48, {8, 8, 16, 0, 0, 0, 1, 1, 1, 4}, 0xFC3u, 0x8u});
    auto bindings = [&](rt::BufferView w) {
        std::vector<rt::Binding> b(12, rt::Binding{rt::BufferView{buf.handle(), 0, 256}});
        for (int i : {0, 1, 6, 8, 9, 10, 11}) b[size_t(i)].texel_format = VK_FORMAT_R32G32B32A32_SFLOAT;
        b[7].texel_format = VK_FORMAT_R32_SINT;
        b[3].view = w;
        b[5].access = rt::Access::Write;
        return b;
    };
    uint32_t push[12] = {};
    rt::Sequence seq(ctx);
    seq.begin();
    REQUIRE_THROWS_WITH(seq.dispatch(p, bindings({buf.handle(), 0, big}), push, 48, 1),
                        Catch::Contains("uniform binding 3 has " + std::to_string(big) + " bytes"));
    if (ctx.info().uniform_offset_alignment > 1)
        REQUIRE_THROWS_WITH(seq.dispatch(p, bindings({buf.handle(), ctx.info().uniform_offset_alignment / 2, 64}), push, 48, 1),
                            Catch::Contains("not aligned to minUniformBufferOffsetAlignment"));
    test::require_no_validation_messages();
}

TEST_CASE("devices can be listed and picked by name or index", "[runtime]") {
    auto devs = rt::Context::list_devices();
    REQUIRE(!devs.empty());
    rt::ContextOptions by_name;
    by_name.validation = 1;
    by_name.device = devs[0].name.substr(0, 4);
    rt::Context a(by_name);
    CHECK(a.info().name.find(by_name.device) != std::string::npos);
    CHECK(a.take_validation_messages().empty());

    rt::ContextOptions by_index;
    by_index.device = "0";
    CHECK(rt::Context(by_index).info().name == devs[0].name);

    rt::ContextOptions none;
    none.device = "no-such-gpu-xyz";
    REQUIRE_THROWS_WITH(rt::Context(none), Catch::Contains("no-such-gpu-xyz") && Catch::Contains(devs[0].name));
}

TEST_CASE("every shader is embedded and unknown ones are reported", "[runtime]") {
    auto names = rt::embedded_shader_names();
    for (const char* n : {"gemm", "activation", "binary", "concat"}) {
        INFO(n);
        CHECK(std::find(names.begin(), names.end(), n) != names.end());
        auto words = rt::find_spirv(n);
        REQUIRE(!words.empty());
        CHECK(words[0] == 0x07230203u);  // SPIR-V magic
    }
    REQUIRE_THROWS_WITH(ops::pipeline(test::gpu(), "not_a_shader", 1, 0, {64}),
                        Catch::Contains("no embedded shader named 'not_a_shader'"));
}

TEST_CASE("pipelines are checked against the shader's own bindings and push constants", "[runtime]") {
    // Every embedded shader reflects: set 0 only, a push block of known layout.
    for (const std::string& n : rt::embedded_shader_names()) {
        INFO(n);
        const rt::ShaderInterface s = rt::reflect_spirv(rt::find_spirv(n), n);
        REQUIRE(!s.bindings.empty());
        CHECK(s.bindings.back() != rt::BindingKind::Other);
        CHECK(s.push_bytes % 4 == 0);
    }
    // The storage-buffer variant of conv2d leaves the vec4 views (6, 8) undeclared.
    const rt::ShaderInterface ssbo = rt::reflect_spirv(rt::find_spirv("conv2d_ssbo"), "conv2d_ssbo");
    REQUIRE(ssbo.bindings.size() == 8);
    CHECK(ssbo.bindings[6] == rt::BindingKind::Other);
    CHECK(ssbo.bindings[5] == rt::BindingKind::StorageBuffer);
    // conv2d reads through texel buffers except its output (5) and workspace (7).
    const rt::ShaderInterface conv = rt::reflect_spirv(rt::find_spirv("conv2d"), "conv2d");
    REQUIRE(conv.bindings.size() == 9);
    for (uint32_t i = 0; i < 9; ++i)
        CHECK((conv.bindings[i] == rt::BindingKind::TexelBuffer) == (i != 5 && i != 7));
    // point_mlp_ubo reads its weights (binding 3) from a uniform buffer; point_mlp
    // from a storage buffer.
    const rt::ShaderInterface ubo = rt::reflect_spirv(rt::find_spirv("point_mlp_ubo"), "point_mlp_ubo");
    REQUIRE(ubo.bindings.size() == 12);
    CHECK(ubo.bindings[3] == rt::BindingKind::UniformBuffer);
    CHECK(ubo.bindings[5] == rt::BindingKind::StorageBuffer);
    CHECK(rt::reflect_spirv(rt::find_spirv("point_mlp"), "point_mlp").bindings[3] == rt::BindingKind::StorageBuffer);
    // point_mlp_shfl reads its weights (2), the ball indices (7, integer texels) and a
    // hidden first layer's weights and bias (10, 11) as texel buffers.
    const rt::ShaderInterface shfl = rt::reflect_spirv(rt::find_spirv("point_mlp_shfl"), "point_mlp_shfl");
    REQUIRE(shfl.bindings.size() == 12);
    for (uint32_t i = 0; i < 12; ++i)
        CHECK((shfl.bindings[i] == rt::BindingKind::TexelBuffer) == (i != 3 && i != 4 && i != 5));
    // activation: x, y and a push block (n, slope).
    const rt::ShaderInterface act = rt::reflect_spirv(rt::find_spirv("activation"), "activation");
    CHECK(act.bindings.size() == 2);
    CHECK(act.push_bytes == 8);
    // Subgroup operations, from the module's GroupNonUniform* capabilities.
    CHECK(shfl.subgroup_ops);
    CHECK(rt::reflect_spirv(rt::find_spirv("fps_subgroup"), "fps_subgroup").subgroup_ops);
    CHECK_FALSE(act.subgroup_ops);
    CHECK_FALSE(ubo.subgroup_ops);
    // A description that disagrees with the shader is refused by name.
    rt::Context& ctx = test::gpu();
    REQUIRE_THROWS_WITH(ops::pipeline(ctx, "activation", 1, 8, {32, ops::kActRelu}),
                        Catch::Contains("shader 'activation' declares 2 bindings; the op passes 1"));
    REQUIRE_THROWS_WITH(ctx.pipelines().get(rt::PipelineDesc{"activation", 2, 8, {32, ops::kActRelu}, 0b01}),
                        Catch::Contains("binding 0 is a storage buffer in the shader, but the op binds a texel buffer"));
    REQUIRE_THROWS_WITH(ctx.pipelines().get(rt::PipelineDesc{"activation", 2, 8, {32, ops::kActRelu}, 0, 0b10}),
                        Catch::Contains("binding 1 is a storage buffer in the shader, but the op binds a uniform buffer"));
    REQUIRE_THROWS_WITH(ops::pipeline(ctx, "activation", 2, 16, {32, ops::kActRelu}),
                        Catch::Contains("declares 8 bytes of push constants; the op pushes 16"));
    REQUIRE_THROWS_WITH(rt::reflect_spirv(std::vector<uint32_t>{1, 2, 3, 4, 5, 6}, "junk"),
                        Catch::Contains("shader 'junk': not a SPIR-V module"));
    test::require_no_validation_messages();
}

TEST_CASE("pipelines are cached per shader and specialization", "[runtime]") {
    rt::Context& ctx = test::gpu();
    const rt::Pipeline& a = ops::pipeline(ctx, "activation", 2, 8, {32, ops::kActRelu});
    size_t n = ctx.pipelines().size();
    const rt::Pipeline& b = ops::pipeline(ctx, "activation", 2, 8, {32, ops::kActRelu});
    CHECK(&a == &b);
    CHECK(ctx.pipelines().size() == n);
    const rt::Pipeline& c = ops::pipeline(ctx, "activation", 2, 8, {32, ops::kActTanh});
    CHECK(&a != &c);
    CHECK(ctx.pipelines().size() == n + 1);
    test::require_no_validation_messages();
}

TEST_CASE("barriers are inserted on hazards and only there", "[runtime]") {
    rt::Context& ctx = test::gpu();
    const uint32_t n = 1000;
    rt::Buffer buf(ctx, 6 * 4096, rt::MemoryKind::Device);
    rt::Buffer host(ctx, 2 * 4096, rt::MemoryKind::Staging);
    auto view = [&](int i) { return rt::BufferView{buf.handle(), VkDeviceSize(i) * 4096, n * 4}; };
    rt::BufferView host_in{host.handle(), 0, n * 4}, host_out{host.handle(), 4096, n * 4};
    std::vector<float> x(n);
    for (uint32_t i = 0; i < n; ++i) x[i] = float(i) - 500.0f;
    std::memcpy(host.mapped(), x.data(), n * 4);

    uint32_t local = ops::elementwise_local_size(ctx.info());
    const rt::Pipeline& relu = ops::pipeline(ctx, "activation", 2, 8, {local, ops::kActRelu});
    const rt::Pipeline& neg = ops::pipeline(ctx, "activation", 2, 8, {local, ops::kActLeaky});
    struct { uint32_t n; float slope; } push{n, -1.0f};
    uint32_t groups = ops::grid_groups(n, local, ctx.info());

    rt::Sequence seq(ctx);
    seq.begin();
    seq.copy(host_in, view(0));                       // upload
    CHECK(seq.barrier_count() == 0);
    seq.dispatch(relu, {{view(0), rt::Access::Read}, {view(1), rt::Access::Write}}, &push, 8, groups);
    CHECK(seq.barrier_count() == 1);                  // RAW on view 0 after the copy
    seq.dispatch(neg, {{view(0), rt::Access::Read}, {view(2), rt::Access::Write}}, &push, 8, groups);
    CHECK(seq.barrier_count() == 1);                  // independent of the relu: no barrier
    seq.dispatch(relu, {{view(1), rt::Access::Read}, {view(3), rt::Access::Write}}, &push, 8, groups);
    CHECK(seq.barrier_count() == 2);                  // RAW on view 1
    seq.dispatch(neg, {{view(4), rt::Access::Read}, {view(3), rt::Access::Write}}, &push, 8, groups);
    CHECK(seq.barrier_count() == 3);                  // WAW on view 3
    seq.dispatch(relu, {{view(2), rt::Access::Read}, {view(4), rt::Access::Write}}, &push, 8, groups);
    CHECK(seq.barrier_count() == 4);                  // WAR on view 4
    seq.copy(view(1), host_out);
    CHECK(seq.barrier_count() == 4);                  // view 1 was written before the last barrier
    seq.end();
    seq.submit_and_wait();
    test::require_no_validation_messages();

    std::vector<float> y(n);
    std::memcpy(y.data(), static_cast<char*>(host.mapped()) + 4096, n * 4);
    for (uint32_t i = 0; i < n; ++i) REQUIRE(y[i] == std::max(x[i], 0.0f));
}

TEST_CASE("profiling records a GPU time per node", "[runtime]") {
    rt::Context& ctx = test::gpu();
    if (!ctx.info().has_timestamps) {
        WARN("device has no timestamps; profiling is unavailable");
        CHECK_FALSE(rt::Sequence(ctx, true).profiling());
        return;
    }
    Graph g;
    int x = g.input("x", {64, 64});
    int h = ops::linear(g, x, g.weight("w", {64, 64}), -1, ops::kActNone, 0.01, "fc");
    g.output(ops::activation(g, ops::kActRelu, h, 0.01, "act"), "y");
    WeightStore w;
    w.add("w", test::random_tensor({64, 64}, 1));
    GpuExecutor exec(ctx, g, w, /*profile=*/true);
    exec.run({{"x", test::random_tensor({64, 64}, 2)}});
    auto times = exec.node_times();
    REQUIRE(times.size() == 2);
    CHECK(times[0].label == "fc");
    CHECK(times[1].label == "act");
    for (auto& t : times) CHECK(t.ms >= 0.0);
    test::require_no_validation_messages();
}

TEST_CASE("validation messages reach the test harness", "[runtime]") {
    // A deliberately invalid call (a zero-sized buffer) on a context of its own,
    // so that the check that fails every other test is known to work.
    rt::ContextOptions o;
    o.validation = 1;
    rt::Context ctx(o);
    VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    bi.size = 0;
    bi.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    VkBuffer b = VK_NULL_HANDLE;
    vkCreateBuffer(ctx.device(), &bi, nullptr, &b);
    if (b) vkDestroyBuffer(ctx.device(), b, nullptr);
    auto msgs = ctx.take_validation_messages();
    REQUIRE(!msgs.empty());
    CHECK(msgs[0].text.find("size") != std::string::npos);
}
