#include "tests/harness.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <sstream>

#include <unistd.h>

namespace vtloc::test {

namespace {
std::unique_ptr<rt::Context> g_ctx;
}

rt::Context& gpu() {
    if (!g_ctx) {
        rt::ContextOptions o;
        o.validation = 1;
        g_ctx = std::make_unique<rt::Context>(o);
    }
    return *g_ctx;
}

bool gpu_created() { return g_ctx != nullptr; }

bool big_tiles_apply() { return gpu().info().type == VK_PHYSICAL_DEVICE_TYPE_CPU; }

void release_gpu() { g_ctx.reset(); }

void require_no_validation_messages() {
    if (!g_ctx) return;
    auto msgs = g_ctx->take_validation_messages();
    std::ostringstream text;
    for (auto& m : msgs) text << "[" << m.severity << "] " << m.text << "\n";
    INFO("validation layer messages:\n" << text.str());
    CHECK(msgs.empty());
}

HostTensor transposed(const HostTensor& t) {
    REQUIRE(t.shape.size() == 2);
    const int64_t R = t.shape[0], C = t.shape[1];
    HostTensor o({C, R}, t.type);
    for (int64_t r = 0; r < R; ++r)
        for (int64_t c = 0; c < C; ++c) o.data[size_t(c * R + r)] = t.data[size_t(r * C + c)];
    return o;
}

HostTensor random_tensor(const Shape& shape, uint32_t seed, float lo, float hi) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dist(lo, hi);
    HostTensor t(shape);
    for (float& v : t.data) v = dist(rng);
    return t;
}

void require_close(const HostTensor& got, const HostTensor& want, Tolerance tol, const std::string& what) {
    INFO(what << ": shape " << shape_str(got.shape) << " vs " << shape_str(want.shape));
    REQUIRE(got.shape == want.shape);
    REQUIRE(got.data.size() == want.data.size());
    size_t bad = 0, worst = 0;
    double worst_excess = -1.0;
    for (size_t i = 0; i < got.data.size(); ++i) {
        double a = got.data[i], b = want.data[i];
        if (a == b) continue;  // equal infinities match (their difference and 0 * inf are NaN)
        // Unequal and either one infinite or NaN: no tolerance admits it (with tol.rel > 0 an infinite
        // want would make the limit infinite and accept anything).
        double limit = std::isfinite(a) && std::isfinite(b) ? tol.abs + tol.rel * std::abs(b) : -1.0;
        double err = std::abs(a - b);
        if (!(err <= limit)) ++bad;  // NaN counts as bad
        double excess = std::isnan(err) ? 1e30 : err - limit;
        if (excess > worst_excess) worst_excess = excess, worst = i;
    }
    INFO(bad << " of " << got.data.size() << " elements outside |a-b| <= " << tol.abs << " + " << tol.rel
             << "*|b|; worst at " << worst << ": got " << (got.data.empty() ? 0.f : got.data[worst])
             << ", want " << (want.data.empty() ? 0.f : want.data[worst]));
    CHECK(bad == 0);
}

TensorMap run_gpu_and_compare(const Graph& g, const WeightStore& w, const TensorMap& inputs, Tolerance tol) {
    TensorMap want = run_cpu(g, w, inputs);
    GpuExecutor exec(gpu(), g, w);
    TensorMap got = exec.run(inputs);
    require_no_validation_messages();
    REQUIRE(got.size() == want.size());
    for (auto& [name, t] : want) require_close(got.at(name), t, tol, "output '" + name + "'");
    return got;
}

// A folder per test process, removed at its exit: the same case runs in several ctest shards at
// once (cpp/check beside long/texel64k/check), and a shared name raced (one wrote a codebook
// cache while the other checked it was removed).
std::string temp_path(const std::string& name) {
    struct Dir {
        std::filesystem::path path = std::filesystem::temp_directory_path() / "vtloc-tests" / std::to_string(::getpid());
        ~Dir() {
            std::error_code ec;
            std::filesystem::remove_all(path, ec);
        }
    };
    static const Dir dir;
    std::filesystem::create_directories(dir.path);
    return (dir.path / name).string();
}

}  // namespace vtloc::test
