#pragma once
// Render-and-compare at an exact pose (SPEC 9; docs/render_compare.md, "At the refined
// poses"). The codebook scores a touch at the grid's hypotheses, which sit up to half a
// sample spacing and half a spin step from any true pose: on a toothed or edged patch
// that offset changes what the gel would feel more than the place does. Once the filter
// has climbed its best modes to continuous poses, each is scored again here: the object
// rendered under the comparison window at that very pose, against the touch's measured
// map, in the codebook score's form. The filter adds it to the refined modes' fits when
// they share the grid's mass (track::PoseTerm, engine/track/tracker.h), so it breaks ties the
// geometry leaves: places where the contacts fit alike but the gel would feel otherwise.
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/ops/codebook_bins.h"
#include "engine/rigid.h"
#include "engine/tensor.h"
#include "engine/track/codebook.h"
#include "engine/track/surface.h"

namespace vtloc::track {

// One touch's measured indentation on the comparison window: [R, C] cells of win_mm
// (window_map), and its press (the codebook's measured_press at o.press_percentile).
struct ShapeWindow {
    HostTensor measured;
    double win_mm = 0;
    float press = 0;
};
ShapeWindow shape_window(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, const ScoreOptions& o);

class PoseShapeScorer {
public:
    // The surface's dense points binned once; a cloud too sparse to render is refused
    // (check_render_density). `o`: the codebook's rendering options (splat, cap, facing).
    explicit PoseShapeScorer(const Surface& s, const CodebookOptions& o = {});
    // The depth along the pose's axis z (from its origin) of the shallowest dense point facing
    // the sensor whose splat disc covers each window cell's centre (row r at v along y, column
    // c at u along x, as the codebook's score reads a measured map); cap where none.
    std::vector<float> render(const Rigid& pose, int R, int C, double win_mm) const;
    // The codebook score at this pose: -weight * sum (e - fit)^2 / (R C press^2), e the measured
    // map less the rendered one pressed `press` past its shallowest cell, fit its least-squares
    // plane (and bowl with `quadratic`); 0 for a touch with no press. With a finite `floor`
    // (log) the score s is robust, log(e^s + e^floor) - log(1 + e^floor): 0 still where the
    // maps agree, and no lower than floor - log(1 + e^floor) however badly one touch's map
    // disagrees (a reader's bad frame costs a bounded amount, as a geometry term's floor).
    double score(const Rigid& pose, const ShapeWindow& m, double weight, bool quadratic, double floor = -INFINITY) const;
    // Host memory: the binned copy of the dense points and the bins.
    uint64_t bytes() const { return 4 * uint64_t(bins_.points.size() + bins_.bins.size()); }

private:
    ops::book::BinnedPoints bins_;
    CodebookOptions o_;
};

}  // namespace vtloc::track
