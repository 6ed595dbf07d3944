// vtloc-bench's tracker stage continues a tour past its last touch (engine/tour_cycle.h).
// "return" must only revisit the tour's own poses, so that the steady touches it times are
// ones a robot could make; "repeat" is the old cycle, kept for comparison.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "engine/tour_cycle.h"

using namespace vtloc;

namespace {

Rigid random_motion(std::mt19937& rng) {
    std::normal_distribution<double> g(0, 1);
    const double w[3] = {0.3 * g(rng), 0.3 * g(rng), 0.3 * g(rng)};
    Rigid m;
    m.R = rotation_of(w);
    m.t = {10 * g(rng), 10 * g(rng), 10 * g(rng)};
    return m;
}

double gap(const Rigid& a, const Rigid& b) {
    double d = 0;
    for (size_t i = 0; i < 9; ++i) d = std::max(d, std::abs(a.R[i] - b.R[i]));
    for (size_t i = 0; i < 3; ++i) d = std::max(d, std::abs(a.t[i] - b.t[i]));
    return d;
}

}  // namespace

TEST_CASE("the bench's returning tour revisits only the tour's own poses", "[bench]") {
    for (size_t n : {1, 2, 7}) {
        std::mt19937 rng{uint32_t(n)};
        std::vector<Rigid> tour(n);
        for (Rigid& m : tour) m = random_motion(rng);
        std::vector<Rigid> poses{Rigid{}};  // the tour's poses, from its first touch
        for (const Rigid& m : tour) poses.push_back(compose(poses.back(), m));
        Rigid x;  // walking the continued tour: touch i must sit where the tour's touch p(i) did
        for (int i = 1; i < int(5 * n + 3); ++i) {
            x = compose(x, tour_motion(tour, "return", i));
            const int period = int(2 * n), j = i % period, p = j <= int(n) ? j : period - j;
            INFO("n " << n << ", touch " << i << " should be the tour's touch " << p);
            REQUIRE(gap(x, poses[size_t(p)]) <= 1e-9);
            CHECK(returned_touch(int(n), i) == p);
        }
        // "repeat" is the tour's motions over again; past the tour it leaves its poses.
        for (int i = 1; i <= int(2 * n); ++i) CHECK(gap(tour_motion(tour, "repeat", i), tour[size_t(i - 1) % n]) == 0);
    }
    std::vector<Rigid> one{Rigid{}};
    CHECK_THROWS_WITH(tour_motion(one, "loop", 1), Catch::Contains("return or repeat"));
    CHECK(known_tour_cycle("return"));  // what the CLI accepts, before its first stage
    CHECK(known_tour_cycle("repeat"));
    CHECK(!known_tour_cycle("loop"));
    CHECK(!known_tour_cycle(""));
    CHECK_THROWS_WITH(tour_motion({}, "return", 1), Catch::Contains("needs a motion"));
    CHECK(returned_touch(3, 0) == 0);
    CHECK_THROWS_WITH(returned_touch(0, 1), Catch::Contains("needs a motion"));
}
