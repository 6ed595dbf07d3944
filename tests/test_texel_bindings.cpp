// Uniform texel-buffer bindings (rt::PipelineDesc::texel_bindings): the limits
// the device reports, a read through one (validation on), and the errors for
// bindings the shader cannot read that way.
#include <catch2/catch.hpp>
#include <cstring>

#include "base/error.h"
#include "runtime/memory.h"
#include "runtime/pipeline.h"
#include "runtime/sequence.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

// max_pool2d.comp reads binding 0 as a texel buffer; a 1x1 kernel copies (binding 2,
// its output as vec4s, is not written at this width).
const rt::Pipeline& copy_pipeline(rt::Context& ctx, uint32_t texel_mask) {
    return ctx.pipelines().get(rt::PipelineDesc{"max_pool2d", 3, 36, {ctx.info().subgroup_size, 1, 1}, texel_mask});
}

struct Push { uint32_t planes, h, w, oh, ow, sh, sw; int32_t ph, pw; };

}  // namespace

TEST_CASE("texel-buffer limits are reported", "[runtime]") {
    const rt::DeviceInfo& d = test::gpu().info();
    CHECK(d.max_texel_elements >= 65536);  // Vulkan's guaranteed minimum
    CHECK(d.texel_offset_alignment >= 1);
    CHECK((d.texel_offset_alignment & (d.texel_offset_alignment - 1)) == 0);
}

TEST_CASE("a texel binding reads a sub-range of a buffer", "[runtime]") {
    rt::Context& ctx = test::gpu();
    const uint64_t align = std::max<uint64_t>({16, ctx.info().texel_offset_alignment, ctx.info().storage_offset_alignment});
    // Input at offset `align`, output at 4 * align: both away from 0, not overlapping.
    rt::Buffer dev(ctx, 4 * align + 64, rt::MemoryKind::Device), staging(ctx, 4 * align + 64, rt::MemoryKind::Staging);
    std::vector<float> v(7);
    for (size_t i = 0; i < v.size(); ++i) v[i] = float(i) * 1.5f - 2.0f;
    std::memcpy(static_cast<char*>(staging.mapped()) + align, v.data(), 28);
    rt::Sequence seq(ctx);
    seq.begin();
    seq.copy({staging.handle(), align, 28}, {dev.handle(), align, 28});
    Push push{1, 1, 7, 1, 7, 1, 1, 0, 0};
    seq.dispatch(copy_pipeline(ctx, 0x1), {{{dev.handle(), align, 28}, rt::Access::Read, VK_FORMAT_R32_SFLOAT},
                                          {{dev.handle(), 4 * align, 28}, rt::Access::Write},
                                          {{dev.handle(), 4 * align, 28}, rt::Access::Write}},
                 &push, sizeof(push), 1);
    seq.copy({dev.handle(), 4 * align, 28}, {staging.handle(), 0, 28});
    seq.end();
    seq.submit_and_wait();
    test::require_no_validation_messages();
    std::vector<float> got(7);
    std::memcpy(got.data(), staging.mapped(), 28);
    CHECK(got == v);
}

TEST_CASE("texel bindings the shader cannot use are refused by name", "[runtime]") {
    rt::Context& ctx = test::gpu();
    rt::Buffer buf(ctx, 256, rt::MemoryKind::Device);
    Push push{1, 1, 4, 1, 4, 1, 1, 0, 0};
    rt::Sequence seq(ctx);
    seq.begin();
    const rt::Pipeline& p = copy_pipeline(ctx, 0x1);
    REQUIRE_THROWS_WITH(seq.dispatch(p, {{{buf.handle(), 0, 16}, rt::Access::Read}, {{buf.handle(), 128, 16}, rt::Access::Write},
                                         {{buf.handle(), 128, 16}, rt::Access::Write}},
                                     &push, sizeof(push), 1),
                        Catch::Contains("max_pool2d") && Catch::Contains("texel binding 0") &&
                            Catch::Contains("texel_format"));
    REQUIRE_THROWS_WITH(seq.dispatch(p, {{{buf.handle(), 0, 16}, rt::Access::ReadWrite, VK_FORMAT_R32_SFLOAT},
                                         {{buf.handle(), 128, 16}, rt::Access::Write},
                                         {{buf.handle(), 128, 16}, rt::Access::Write}},
                                     &push, sizeof(push), 1),
                        Catch::Contains("read-only"));
    REQUIRE_THROWS_WITH(seq.dispatch(p, {{{buf.handle(), 0, 8}, rt::Access::Read, VK_FORMAT_R32G32B32A32_SFLOAT},
                                         {{buf.handle(), 128, 16}, rt::Access::Write},
                                         {{buf.handle(), 128, 16}, rt::Access::Write}},
                                     &push, sizeof(push), 1),
                        Catch::Contains("smaller than one texel"));
    seq.end();
    REQUIRE_THROWS_WITH(copy_pipeline(ctx, 0x8), Catch::Contains("does not have"));
    test::require_no_validation_messages();
}
