// The renderer against the 49 real ball presses of the shipped calibration
// (engine/sim/reality_check.h).
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>

#include "engine/sensor/calibration.h"
#include "engine/sim/reality_check.h"
#include "tests/harness.h"

using namespace vtloc;
using namespace vtloc::sim;

TEST_CASE("sim: rendered ball presses match the real frames", "[sim]") {
    Calibration c = load_calibration(default_calibration_path());
    RealityOptions o;
    o.png_path = test::temp_path("sim_reality_check.png");
    std::filesystem::remove(o.png_path);
    RealityReport rep = reality_check(c, o);
    REQUIRE(rep.frames.size() == 49);
    for (const RealityFrame& f : rep.frames) {
        INFO("frame " << f.index << ": radius ratio " << f.radius_ratio << ", centres " << f.centre_dist
                      << " px apart, |dRGB| in " << f.drgb_inside << " out " << f.drgb_outside);
        REQUIRE(f.real.found);
        REQUIRE(f.sim.found);
        // Detected contact radii agree within 20 % on every frame.
        CHECK(f.radius_ratio > 0.8);
        CHECK(f.radius_ratio < 1.2);
        // The goal is 3 px on EVERY frame; it is NOT met (max 7.2 px),
        // so this bound is the one that holds. The real halo is lopsided
        // towards the upper right: in the ring 2..12 px outside the annotated
        // circle the real frames' stored channel 0 (blue) drops up to ~2x
        // more than the render's on that side (e.g. frame 6: -70 vs -33),
        // strongest for presses low and right in the image, while the other
        // channels and quadrants roughly agree. Ruled out as causes: the
        // domed gel (depth_bg; contact against it moves the render's centre
        // towards the image centre, max 7.0-7.7 px), wider/narrower or
        // stronger drapes (max 6.9-8.0 px), and a pixel-centre or axis slip
        // (render minus annotation is ~0.2 px in x and follows the table's
        // own position terms in y). A one-sided, blue-only loss of light
        // beyond the contact (light-guide shadowing, not in the local
        // polynomial model) brings the max to ~4.8 px but raises |dRGB|
        // inside above 14.5, so it is not in the renderer.
        // Rim-based detectors do not meet 3 px either (tried, not kept):
        // a circle fitted to the steepest outward drop of the change
        // magnitude along 72 rays (robust, iterated) gives real vs
        // rendered median 2.4-3.3 px, max 7.9-9.1 px (18-28 frames over
        // 3 px). The rim is soft (~6 px), and weak where the disc's colour
        // is close to the background's. cv::HoughCircles is worse (median
        // 3.2 px+, outliers). The pole (minimum of the change inside the
        // contact) finds the rendered centre within 1.4 px of the
        // annotation, but real vs rendered still has a max of 5.2 px. On
        // the real frames, rim and pole agree with each other and sit up to
        // 4.5 px above the annotation (frames 20, 22, 30, 36, 45).
        CHECK(f.centre_dist < 8.5);
    }
    CHECK(rep.median_radius_err < 0.08);
    CHECK(rep.median_centre_dist < 3.5);
    // Why 3 px on every frame cannot be reached from the annotations: the
    // offsets left after their best quadratic fit in the press position
    // (in-sample, so optimistic) still reach 3.6 px. Frames 6 and 24 share one
    // annotation, (110, 82) r 17, yet their real contacts are detected 1.7 px
    // apart: any renderer draws both the same. If the floor ever falls below
    // 3 px (new calibration data), the goal becomes reachable and this fails.
    CHECK(rep.floor_max_centre_dist > 3.0);
    CHECK(rep.floor_median_centre_dist < rep.median_centre_dist);
    const RealityFrame &f6 = rep.frames[6], &f24 = rep.frames[24];
    CHECK(f6.annotated_cx == f24.annotated_cx);
    CHECK(f6.annotated_cy == f24.annotated_cy);
    CHECK(std::hypot(f6.real.cx - f24.real.cx, f6.real.cy - f24.real.cy) > 1.0);
    CHECK(std::hypot(f6.sim.cx - f24.sim.cx, f6.sim.cy - f24.sim.cy) < 1e-9);
    // The README's undeformed, no-blur baseline: 14.5 inside, 5.0 outside.
    CHECK(rep.mean_drgb_inside < 14.5);
    CHECK(rep.mean_drgb_outside < 4.5);
    CHECK(std::filesystem::file_size(o.png_path) > 10000);
}
