// Test runner: the Khronos validation layer is always on, and a test after
// which the layer has reported anything fails the run, naming the test.
#define CATCH_CONFIG_RUNNER
#define CATCH_CONFIG_EXTERNAL_INTERFACES
#include <catch2/catch.hpp>
#include <cstdlib>
#include <iostream>

#include "tests/harness.h"

namespace {
bool g_unreported_messages = false;

struct ValidationListener : Catch::TestEventListenerBase {
    using TestEventListenerBase::TestEventListenerBase;
    void testCaseEnded(const Catch::TestCaseStats& stats) override {
        if (!vtloc::test::gpu_created()) return;
        auto msgs = vtloc::test::gpu().take_validation_messages();
        if (msgs.empty()) return;
        g_unreported_messages = true;
        std::cerr << "FAILED: validation messages during test '" << stats.testInfo.name << "':\n";
        for (auto& m : msgs) std::cerr << "  [" << m.severity << "] " << m.text << "\n";
    }
};
CATCH_REGISTER_LISTENER(ValidationListener)
}  // namespace

int main(int argc, char** argv) {
    setenv("VTLOC_VALIDATION", "1", 1);
    int result = Catch::Session().run(argc, argv);
    vtloc::test::release_gpu();
    return result != 0 ? result : (g_unreported_messages ? 1 : 0);
}
