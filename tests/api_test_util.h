#pragma once
// Helpers for the public-API tests ([api]): shipped paths, a validated
// context, and the one-line api::Error check.
#include <catch2/catch.hpp>
#include <algorithm>
#include <string>

#include "vtloc/vtloc.h"

namespace vtloc::test {

inline std::string source_path(const std::string& rel) { return std::string(VTLOC_SOURCE_DIR) + "/" + rel; }
inline std::string tiny_model() { return source_path("weights_tools/goldens/vtloc-tiny.safetensors"); }
inline std::string shipped_model() { return source_path("models/vtloc-r18-half-random.safetensors"); }

inline api::ContextOptions validated() {
    api::ContextOptions o;
    o.validation = api::Validation::On;
    return o;
}

// A gentle cap pressed into the gel at (r0, c0) mm from the frame's corner, tilted by `tilt` mm
// per mm along x (120 x 160 at the dataset's 0.1245 mm).
inline api::GelShape gel_cap(double r0, double c0, double tilt) {
    api::GelShape g;
    g.height = 120, g.width = 160, g.mm_per_px = 0.1245;
    for (int r = 0; r < g.height; ++r)
        for (int c = 0; c < g.width; ++c) {
            const double y = r * g.mm_per_px - r0, x = c * g.mm_per_px - c0;
            g.depth_mm.push_back(float(std::max(0.0, 0.8 - (x * x + y * y) / 40.0 + tilt * x)));
        }
    return g;
}

// Fails the test if the context's validation layer said anything.
inline void require_no_validation(api::Context& ctx) {
    auto msgs = ctx.take_validation_messages();
    std::string text;
    for (auto& m : msgs) text += m + "\n";
    INFO("validation layer messages:\n" << text);
    CHECK(msgs.empty());
}

// Runs f, which must throw vtloc::api::Error; returns its message after
// checking that it is one line.
template <class F>
std::string api_error(F&& f) {
    try {
        f();
    } catch (const api::Error& e) {
        std::string m = e.what();
        INFO("message: " << m);
        CHECK(m.find('\n') == std::string::npos);
        CHECK(!m.empty());
        return m;
    } catch (const std::exception& e) {
        FAIL("threw another type than vtloc::api::Error: " << e.what());
    }
    FAIL("did not throw");
    return {};
}

}  // namespace vtloc::test
