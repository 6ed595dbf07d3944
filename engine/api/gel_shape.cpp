// api::GelShapeReader: the gel's shape from a frame (engine/sensor's pipeline on the GPU).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "base/atomic_write.h"

#include "engine/api/api_internal.h"
#include "engine/check/graph_check.h"
#include "engine/io/image.h"
#include "engine/io/image_mat.h"
#include "engine/sensor/frame_check.h"
#include "engine/sensor/gel_shape_gpu.h"
#include "engine/sensor/lighting.h"

namespace vtloc::api {

struct GelShapeReader::Impl {
    sensor::GelShapeGpu gpu;
    bool match_lighting;
    int threads;  // the tables' host threads, for a check's rebuild of them
    std::mutex mu;  // reads take turns: the GPU pipeline's buffers are the reader's own (Python releases the GIL)
    Impl(rt::Context& ctx, sensor::Calibration c, sensor::GradientLut lut, sensor::ShapeOptions o, bool match, int threads)
        : gpu(ctx, std::move(c), std::move(lut), o), match_lighting(match), threads(threads) {}
    std::pair<std::vector<uint8_t>, std::vector<uint8_t>> prepared(const TactileImage& frame, const TactileImage* empty,
                                                                   const std::string& frame_name, const std::string& empty_name) const;
};

namespace {

// An RGB frame as the calibration's stored channel order (BGR) at its size: resampled (area) when
// larger with the same aspect; any other size is an error naming both.
std::vector<uint8_t> to_calibration(const TactileImage& im, const sensor::Calibration& c, const std::string& what) {
    if (im.height <= 0 || im.width <= 0 || im.rgb.size() != size_t(im.height) * size_t(im.width) * 3)
        throw Error(what + ": not an RGB image");
    const std::string sizes = std::to_string(im.width) + "x" + std::to_string(im.height) + " for the calibration's " +
                              std::to_string(c.width) + "x" + std::to_string(c.height);
    if (int64_t(im.width) * c.height != int64_t(im.height) * c.width)
        throw Error(what + ": " + sizes + ": another aspect (crop it to the sensor's)");
    if (im.width < c.width) throw Error(what + ": " + sizes + ": smaller than the calibration");
    cv::Mat rgb(im.height, im.width, CV_8UC3, const_cast<uint8_t*>(im.rgb.data())), bgr;
    cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
    if (im.width != c.width) cv::resize(bgr, bgr, cv::Size(c.width, c.height), 0, 0, cv::INTER_AREA);
    return std::vector<uint8_t>(bgr.datastart, bgr.dataend);
}

GelShape to_api(const sensor::GelShape& s, double mm_per_px) {
    GelShape out;
    out.height = s.height, out.width = s.width, out.mm_per_px = mm_per_px;
    out.depth_mm = s.depth_mm, out.grad_row = s.grad_row, out.grad_col = s.grad_col, out.mask = s.mask;
    return out;
}

}  // namespace

GelShapeReader::GelShapeReader(Context& context, const GelShapeOptions& o) {
    guarded([&] {
        if (!(o.mask_threshold > 0) || o.iterations < 1 || o.iterations > 10000)
            throw Error("gel shape: mask_threshold must be > 0 and iterations 1..10000");
        if (o.levels < 0 || o.levels > 8 || (o.levels > 0 && (o.coarse_iterations < 1 || o.coarse_iterations > 10000)))
            throw Error("gel shape: levels must be 0..8 and, with levels, coarse_iterations 1..10000");
        if (o.threads < 0 || o.threads > 256) throw Error("gel shape: threads must be 0..256 (0: up to 4)");
        sensor::Calibration c = sensor::load_calibration(o.calibration.empty() ? sensor::default_calibration_path() : o.calibration);
        sensor::GradientLut lut = sensor::build_gradient_lut(c, o.threads);
        static_assert(sensor::kRenderedMaskThreshold == 0.05, "GelShapeOptions::rendered_frames() repeats it");
        // (and the rendered frames' solve, sensor::rendered_frame_options(): tests/test_api_gel_shape.cpp checks they agree)
        sensor::ShapeOptions so;
        so.mask_threshold = o.mask_threshold, so.sor_iterations = o.iterations;
        so.sor_levels = o.levels, so.sor_coarse_iterations = o.coarse_iterations;
        impl_ = std::make_unique<Impl>(ContextAccess::rt(context), std::move(c), std::move(lut), so, o.match_lighting, o.threads);
    });
}

GelShapeReader::~GelShapeReader() = default;
GelShapeReader::GelShapeReader(GelShapeReader&&) noexcept = default;
GelShapeReader& GelShapeReader::operator=(GelShapeReader&&) noexcept = default;

int GelShapeReader::height() const { return impl_->gpu.calibration().height; }
int GelShapeReader::width() const { return impl_->gpu.calibration().width; }

// The frame and the empty frame as the GPU pipeline takes them: the calibration's size and
// channel order, checked, the frame's lighting matched to the empty one's where asked.
std::pair<std::vector<uint8_t>, std::vector<uint8_t>> GelShapeReader::Impl::prepared(const TactileImage& frame, const TactileImage* empty,
                                                                                     const std::string& frame_name,
                                                                                     const std::string& empty_name) const {
    const sensor::Calibration& c = gpu.calibration();
    std::vector<uint8_t> f = to_calibration(frame, c, frame_name);
    std::vector<uint8_t> e = empty ? to_calibration(*empty, c, empty_name) : c.press_f0;
    if (e.empty()) throw Error("gel shape: this calibration has no empty frame; give the sensor's own");
    sensor::check_gel_frame(f, frame_name);
    if (empty) sensor::check_gel_frame(e, empty_name);
    if (match_lighting) f = sensor::match_lighting(f, e);
    return {std::move(f), std::move(e)};
}

GelShape GelShapeReader::read(const TactileImage& frame, const TactileImage* empty, const std::string& frame_name,
                              const std::string& empty_name) {
    return guarded([&] {
        const sensor::Calibration& c = impl_->gpu.calibration();
        const auto [f, e] = impl_->prepared(frame, empty, frame_name, empty_name);
        std::unique_lock<std::mutex> lock(impl_->mu);
        const sensor::GelShape s = impl_->gpu.run(f, e);
        lock.unlock();
        return to_api(s, c.mm_per_px);
    });
}

void GelShapeReader::check_frame(const TactileImage& frame, const TactileImage* empty, const std::string& frame_name,
                                 const std::string& empty_name) const {
    guarded([&] { (void)impl_->prepared(frame, empty, frame_name, empty_name); });
}

GelShapeAccess::Checker::Checker(GelShapeReader& r, rt::Context& ctx) : reader_(r), ctx_(ctx) {}
GelShapeAccess::Checker::~Checker() = default;

GelShapeAccess::Checked GelShapeAccess::Checker::check(const TactileImage& frame, const TactileImage* empty,
                                                       const std::string& frame_name, const std::string& empty_name) {
    const auto [f, e] = reader_.impl_->prepared(frame, empty, frame_name, empty_name);
    sensor::GelShapeGpu& gpu = reader_.impl_->gpu;
    const std::lock_guard<std::mutex> lock(reader_.impl_->mu);
    if (!exec_) {  // the reader keeps its tables on the device only: the CPU reference builds them again
        weights_ = std::make_unique<WeightStore>(gpu.weights_of(sensor::build_gradient_lut(gpu.calibration(), reader_.impl_->threads)));
        exec_ = std::make_unique<GpuExecutor>(ctx_, gpu.graph(), *weights_, false, /*keep_all=*/true);
    }
    Checked c{check::check_graph(*exec_, gpu.graph(), *weights_, gpu.inputs_of(f, e)), {}, {}};
    const double mm_per_px = gpu.calibration().mm_per_px;
    c.read = to_api(gpu.run(f, e), mm_per_px);
    c.reference = to_api(gpu.shape_of(c.graph.cpu_outputs), mm_per_px);
    return c;
}

namespace {

// A grey map in [0, top] as a 3-channel panel, scaled up and captioned.
cv::Mat panel(const cv::Mat& bgr, const std::string& caption, int scale) {
    cv::Mat big;
    cv::resize(bgr, big, cv::Size(), scale, scale, cv::INTER_NEAREST);
    cv::Mat out(big.rows + 28, big.cols, CV_8UC3, cv::Scalar(245, 245, 245));
    big.copyTo(out(cv::Rect(0, 28, big.cols, big.rows)));
    cv::putText(out, caption, cv::Point(6, 20), cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(30, 30, 30), 1, cv::LINE_AA);
    return out;
}

cv::Mat coloured(const std::vector<float>& v, int H, int W, double top) {
    cv::Mat g(H, W, CV_8U);
    for (int i = 0; i < H * W; ++i) g.ptr<uint8_t>()[i] = uint8_t(std::clamp(255.0 * double(v[size_t(i)]) / std::max(top, 1e-9), 0.0, 255.0));
    cv::Mat c;
    cv::applyColorMap(g, c, cv::COLORMAP_INFERNO);
    return c;
}

}  // namespace

std::vector<std::string> write_gel_shape(const std::string& dir, const GelShape& s, const TactileImage& frame) {
    return guarded([&] {
        const int H = s.height, W = s.width;
        const size_t HW = size_t(H) * size_t(W);
        if (H <= 0 || s.depth_mm.size() != HW || s.mask.size() != HW || s.grad_row.size() != HW || s.grad_col.size() != HW)
            throw Error(dir + ": not a gel shape");
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        const std::string height = dir + "/height.png", ply = dir + "/shape.ply", pic = dir + "/shape.png";
        cv::Mat um(H, W, CV_16UC1);
        for (size_t i = 0; i < HW; ++i) um.ptr<uint16_t>()[i] = uint16_t(std::clamp(std::lround(double(s.depth_mm[i]) * 1000.0), 0L, 65535L));
        io::write_png(height, um);
        std::string text;
        size_t n = 0;
        char line[96];
        for (int r = 0; r < H; ++r)
            for (int c = 0; c < W; ++c)
                if (s.mask[size_t(r) * W + size_t(c)]) {
                    std::snprintf(line, sizeof line, "%.4f %.4f %.5f\n", c * s.mm_per_px, r * s.mm_per_px, double(s.depth_mm[size_t(r) * W + size_t(c)]));
                    text += line, ++n;
                }
        write_file_atomic(ply, "ply\nformat ascii 1.0\ncomment the gel's indentation in the contact, mm (vtloc shape)\nelement vertex " +
                                   std::to_string(n) + "\nproperty float x\nproperty float y\nproperty float z\nend_header\n" + text);
        std::vector<float> slope(HW), mask(HW);
        double deepest = 0;
        for (size_t i = 0; i < HW; ++i) {
            slope[i] = std::hypot(s.grad_row[i], s.grad_col[i]), mask[i] = s.mask[i];
            deepest = std::max(deepest, double(s.depth_mm[i]));
        }
        cv::Mat rgb(frame.height, frame.width, CV_8UC3, const_cast<uint8_t*>(frame.rgb.data())), f;
        cv::cvtColor(rgb, f, cv::COLOR_RGB2BGR);
        cv::resize(f, f, cv::Size(W, H), 0, 0, cv::INTER_AREA);
        const int k = std::max(1, 320 / W);
        char cap[64];
        std::snprintf(cap, sizeof cap, "height (0..%.2f mm)", deepest);
        cv::Mat sheet;
        cv::hconcat(std::vector<cv::Mat>{panel(f, "frame", k), panel(coloured(slope, H, W, 1.5), "slope (0..1.5)", k),
                                         panel(coloured(s.depth_mm, H, W, deepest), cap, k), panel(coloured(mask, H, W, 1), "contact", k)},
                    sheet);
        io::write_png(pic, sheet);
        return std::vector<std::string>{height, ply, pic};
    });
}

}  // namespace vtloc::api

namespace vtloc::api {

GelShape load_indentation(const std::string& path, double mm_per_px) {
    return guarded([&] {
        if (!(mm_per_px > 0) || !std::isfinite(mm_per_px)) throw Error(path + ": mm_per_px must be a positive number");
        const io::DepthImage d = io::load_depth_image(path);
        GelShape s;
        s.height = d.height, s.width = d.width, s.mm_per_px = mm_per_px;
        s.depth_mm.resize(d.depth.size());
        s.mask.resize(d.depth.size());
        for (size_t i = 0; i < d.depth.size(); ++i) s.depth_mm[i] = float(d.depth[i]) * 1e-3f, s.mask[i] = d.depth[i] > 0;
        return s;
    });
}

}  // namespace vtloc::api
