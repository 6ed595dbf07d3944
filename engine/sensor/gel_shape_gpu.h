#pragma once
// The gel's shape from a frame on the GPU (SPEC 9): op gel_gradient, the
// contact mask on the CPU (engine/sensor/gel_shape: OpenCV's morphology on
// 120 x 160 pixels), then op masked_poisson. Holds the calibration's tables as
// resident weights and one executor per graph.
#include <cstdint>
#include <memory>
#include <vector>

#include "engine/sensor/calibration.h"
#include "engine/sensor/gel_shape.h"

namespace vtloc {
namespace rt {
class Context;
}
namespace sensor {

class GelShapeGpu {
public:
    GelShapeGpu(rt::Context& ctx, Calibration calib, GradientLut lut, ShapeOptions options = {});
    ~GelShapeGpu();
    GelShapeGpu(const GelShapeGpu&) = delete;
    GelShapeGpu& operator=(const GelShapeGpu&) = delete;

    // frame, empty: the calibration's size, its stored channel order.
    GelShape run(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty);
    const Calibration& calibration() const { return calib_; }

private:
    struct Impl;
    Calibration calib_;
    ShapeOptions opt_;
    std::unique_ptr<Impl> impl_;
};

}  // namespace sensor
}  // namespace vtloc
