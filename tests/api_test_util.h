#pragma once
// Helpers for the public-API tests ([api]): shipped paths, a validated
// context, and the one-line api::Error check.
#include <catch2/catch.hpp>
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
