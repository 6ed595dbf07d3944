#pragma once
// The gel's shape from a frame on the GPU (SPEC 9): ops gel_gradient,
// gel_contact_mask and masked_poisson in one graph, one submit a frame. Holds
// the calibration's tables on the device only: the host's copy (25 MB) goes
// after the upload.
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "engine/executor.h"
#include "engine/sensor/calibration.h"
#include "engine/sensor/gel_shape.h"
#include "engine/weights.h"

namespace vtloc {
namespace rt {
class Context;
}
namespace sensor {

class GelShapeGpu {
public:
    // profile: GPU timestamps per node (node_times() after run(); the benchmark's breakdown).
    GelShapeGpu(rt::Context& ctx, Calibration calib, GradientLut lut, ShapeOptions options = {}, bool profile = false);
    ~GelShapeGpu();
    GelShapeGpu(const GelShapeGpu&) = delete;
    GelShapeGpu& operator=(const GelShapeGpu&) = delete;

    // frame, empty: the calibration's size, its stored channel order.
    GelShape run(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty);
    const Calibration& calibration() const { return calib_; }
    // GPU ms per node of the last run (label, ms); empty unless profiling.
    std::vector<std::pair<std::string, double>> node_times() const;
    // What run() executes: its graph, the tables as weights, and a frame's inputs (check_graph's
    // case: vtloc check --tracker --shapes checks the graph node by node on each frame). The
    // weights from `lut`, which must be the tables the pipeline was made with, built again
    // (build_gradient_lut gives the same bits every time, on any number of threads).
    const Graph& graph() const;
    WeightStore weights_of(GradientLut lut) const;
    TensorMap inputs_of(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty) const;
    GelShape shape_of(const TensorMap& out) const;  // the graph's outputs as a shape (depth in mm)

private:
    int solve(Graph& g, int grad, int mask, int H, int W) const;
    struct Impl;
    Calibration calib_;
    ShapeOptions opt_;
    std::unique_ptr<Impl> impl_;
};

}  // namespace sensor
}  // namespace vtloc
