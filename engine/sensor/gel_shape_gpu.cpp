#include "engine/sensor/gel_shape_gpu.h"

#include "base/error.h"
#include "engine/executor.h"
#include "engine/ops/build.h"
#include "engine/ops/gel_ops.h"

namespace vtloc::sensor {

struct GelShapeGpu::Impl {
    Graph graph;
    std::unique_ptr<GpuExecutor> exec;
};

namespace {

WeightStore tables(GradientLut lut, int64_t H, int64_t W) {
    if (lut.height != H || lut.width != W) throw Error("gel shape: the gradient table belongs to another calibration");
    if (lut.linear.size() != size_t(H * W * 6)) throw Error("gel shape: the gradient table has no linear inverse");
    const int64_t n = lut.n, T = int64_t(lut.tiles_y) * lut.tiles_x;
    WeightStore w;
    w.add("gel.tables", HostTensor({T, n * n * n, 2}, std::move(lut.table)));
    w.add("gel.linear", HostTensor({H, W, 6}, std::move(lut.linear)));
    return w;
}

}  // namespace

// The height from the gradient and mask: ops::gel::masked_poisson_multilevel's steps as nodes
// (gel.height.1, .2, ...: the coarse grids, coarsest solved first).
int GelShapeGpu::solve(Graph& g, int grad, int mask, int H, int W) const {
    const int levels = ops::gel::poisson_levels(H, W, opt_.sor_levels);
    std::vector<int> grads{grad}, masks{mask};
    for (int l = 1; l <= levels; ++l) {
        const std::string at = "gel.height." + std::to_string(l);
        grads.push_back(ops::mean_pool2(g, grads.back(), at + ".gradient"));
        masks.push_back(ops::mean_pool2(g, masks.back(), at + ".mask"));
    }
    int z = -1;
    for (int l = levels; l >= 0; --l) {
        const std::string at = l ? "gel.height." + std::to_string(l) : "gel.height";
        const int start = z < 0 ? -1 : ops::poisson_prolong(g, z, masks[size_t(l)], at + ".start");
        z = ops::masked_poisson(g, grads[size_t(l)], masks[size_t(l)], l ? opt_.sor_coarse_iterations : opt_.sor_iterations,
                                opt_.sor_omega, at, start);
    }
    return z;
}

GelShapeGpu::GelShapeGpu(rt::Context& ctx, Calibration calib, GradientLut lut, ShapeOptions options, bool profile)
    : calib_(std::move(calib)), opt_(options), impl_(std::make_unique<Impl>()) {
    const int64_t H = calib_.height, W = calib_.width, n = lut.n, T = int64_t(lut.tiles_y) * lut.tiles_x;
    const int tiles_y = lut.tiles_y, tiles_x = lut.tiles_x;
    // Uploaded by the executor, then dropped at the end of the constructor: reads need only the device's.
    const WeightStore weights = tables(std::move(lut), H, W);
    Graph& g = impl_->graph;
    const int grad = ops::gel_gradient(g, g.input("frame", {H, W, 3}), g.input("empty", {H, W, 3}),
                                       g.weight("gel.tables", {T, n * n * n, 2}), g.weight("gel.linear", {H, W, 6}), n,
                                       tiles_y, tiles_x, opt_.gentle_slope, "gel.gradient");
    const int mask = ops::gel_contact_mask(g, grad, opt_.mask_threshold, opt_.close_radius, opt_.open_radius, "gel.mask");
    g.output(grad, "gradient");
    g.output(mask, "mask");
    g.output(solve(g, grad, mask, int(H), int(W)), "height");
    impl_->exec = std::make_unique<GpuExecutor>(ctx, g, weights, profile);
}

GelShapeGpu::~GelShapeGpu() = default;

std::vector<std::pair<std::string, double>> GelShapeGpu::node_times() const {
    std::vector<std::pair<std::string, double>> t;
    for (const rt::Sequence::NodeTime& n : impl_->exec->node_times()) t.emplace_back(n.label, n.ms);
    return t;
}

const Graph& GelShapeGpu::graph() const { return impl_->graph; }
WeightStore GelShapeGpu::weights_of(GradientLut lut) const {
    WeightStore w = tables(std::move(lut), calib_.height, calib_.width);
    for (const Value& v : impl_->graph.values())  // a table of another grid: an error naming it, here
        if (v.kind == ValueKind::Weight) (void)w.get(v.name, v.shape);
    return w;
}

TensorMap GelShapeGpu::inputs_of(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty) const {
    const int H = calib_.height, W = calib_.width;
    const size_t HW = size_t(H) * size_t(W);
    if (frame.size() != HW * 3 || empty.size() != HW * 3)
        throw Error("gel shape: frames must be " + std::to_string(W) + "x" + std::to_string(H) + " RGB, the calibration's size");
    HostTensor f({H, W, 3}), e({H, W, 3});
    for (size_t i = 0; i < HW * 3; ++i) f.data[i] = frame[i], e.data[i] = empty[i];
    return {{"frame", f}, {"empty", e}};
}

GelShape GelShapeGpu::run(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty) {
    return shape_of(impl_->exec->run(inputs_of(frame, empty)));
}

GelShape GelShapeGpu::shape_of(const TensorMap& out) const {
    const int H = calib_.height, W = calib_.width;
    const size_t HW = size_t(H) * size_t(W);
    const HostTensor &grad = out.at("gradient"), &mask = out.at("mask"), &z = out.at("height");
    GelShape s;
    s.height = H, s.width = W;
    s.grad_row.resize(HW), s.grad_col.resize(HW), s.mask.resize(HW);
    for (size_t p = 0; p < HW; ++p) {
        s.grad_row[p] = grad.data[2 * p], s.grad_col[p] = grad.data[2 * p + 1];
        s.mask[p] = mask.data[p] > 0.5f;
    }
    s.depth_mm.resize(HW);
    for (size_t p = 0; p < HW; ++p) s.depth_mm[p] = s.mask[p] ? float(double(z.data[p]) * calib_.mm_per_px) : 0.0f;
    return s;
}

}  // namespace vtloc::sensor
