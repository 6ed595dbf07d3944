// api::MadeOnce (engine/api/made_once.h): what with_options' trackers share is made once,
// by whichever asks first, and a make that fails leaves it to the next ask.
#include <catch2/catch.hpp>
#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include "engine/api/made_once.h"

using namespace vtloc;

TEST_CASE("made once: eight threads asking at once get one object, made once", "[api][threads]") {
    api::MadeOnce<int> held;
    CHECK(held.peek() == nullptr);
    std::atomic<int> makes{0};
    std::vector<std::shared_ptr<int>> got(8);
    std::vector<std::thread> threads;
    for (size_t i = 0; i < got.size(); ++i)
        threads.emplace_back([&, i] {
            got[i] = held.get([&] {
                ++makes;
                return std::make_shared<int>(7);
            });
        });
    for (std::thread& t : threads) t.join();
    CHECK(makes == 1);
    for (const auto& p : got) CHECK(p.get() == got[0].get());
    CHECK(held.peek().get() == got[0].get());
}

TEST_CASE("made once: a make that throws leaves nothing, and the next ask makes it", "[api]") {
    api::MadeOnce<int> held;
    CHECK_THROWS_WITH(held.get([]() -> std::shared_ptr<int> { throw std::runtime_error("no codebook file"); }),
                      Catch::Contains("no codebook file"));
    CHECK(held.peek() == nullptr);
    CHECK(*held.get([] { return std::make_shared<int>(3); }) == 3);
    CHECK(*held.get([] { return std::make_shared<int>(4); }) == 3);  // made: the second make never runs
}
