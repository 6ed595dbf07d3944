#include "engine/sim/point_filtering.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/sim/touch_renderer.h"

namespace vtloc::sim {

namespace {

std::vector<float> to_float(const std::vector<uint8_t>& v) { return std::vector<float>(v.begin(), v.end()); }

// The frame at the simulator's size, as floats.
std::vector<float> fit(const Frame8& f, int height, int width, const char* what) {
    if (f.height <= 0 || f.width <= 0 || f.data.size() != size_t(f.height) * size_t(f.width) * 3)
        throw Error(std::string("point filtering: the ") + what + " is not a " + std::to_string(f.height) + "x" +
                    std::to_string(f.width) + " 3-channel image");
    if (f.height == height && f.width == width) return to_float(f.data);
    cv::Mat src(f.height, f.width, CV_8UC3, const_cast<uint8_t*>(f.data.data())), dst;
    cv::resize(src, dst, cv::Size(width, height), 0, 0, cv::INTER_AREA);
    return std::vector<float>(dst.data, dst.data + size_t(height) * size_t(width) * 3);
}

}  // namespace

PointFilter::PointFilter(const Calibration& calib, const io::TriangleMesh& mesh, std::optional<double> mm_per_px,
                         const std::vector<Point3>& candidates, const std::vector<Point3>& normals,
                         std::optional<Frame8> background, const PointFilterOptions& options)
    : height_(calib.height), width_(calib.width), options_(options) {
    if (candidates.size() != normals.size()) throw Error("point filtering: one normal per candidate needed");
    if (options.spins < 1) throw Error("point filtering: at least one spin needed");
    TouchRenderer renderer(calib, mesh, mm_per_px);
    Appearance look;
    look.noise_sigma = 0;  // the renders are templates: no noise
    const std::vector<float> render_bg = to_float(renderer.background_frame(look));
    observed_bg_ = background ? fit(*background, height_, width_, "background frame") : render_bg;
    for (size_t i = 0; i < candidates.size(); ++i) {
        std::vector<std::vector<float>> spins;
        for (int s = 0; s < options.spins; ++s) {
            TouchParams p;
            p.press_mm = options.press_mm;
            p.spin_deg = 360.0 * s / options.spins;
            const Touch t = renderer.render(candidates[i], normals[i], p, look, 0);
            if (!t.ok) continue;
            spins.push_back(prepare(Frame8{height_, width_, t.image}, render_bg));
        }
        if (spins.empty()) ++unrenderable_;
        renders_.push_back(std::move(spins));
    }
}

// Background-subtracted, channel-averaged, blurred, then zero-mean and unit
// norm, so that NCC is a dot product; empty when the image is flat.
std::vector<float> PointFilter::prepare(const Frame8& frame, const std::vector<float>& background) const {
    const std::vector<float> f = fit(frame, height_, width_, "tactile frame");
    cv::Mat gray(height_, width_, CV_32F);
    float* g = gray.ptr<float>();
    for (size_t i = 0; i < size_t(height_) * size_t(width_); ++i)
        g[i] = ((f[i * 3] - background[i * 3]) + (f[i * 3 + 1] - background[i * 3 + 1]) +
                (f[i * 3 + 2] - background[i * 3 + 2])) / 3.0f;
    if (options_.blur_sigma_px > 0)
        cv::GaussianBlur(gray, gray, cv::Size(0, 0), options_.blur_sigma_px, options_.blur_sigma_px, cv::BORDER_REFLECT);
    std::vector<float> v(g, g + size_t(height_) * size_t(width_));
    double mean = 0;
    for (float x : v) mean += x;
    mean /= double(v.size());
    double norm = 0;
    for (float& x : v) {
        x = float(x - mean);
        norm += double(x) * double(x);
    }
    norm = std::sqrt(norm);
    if (!(norm > 1e-3)) return {};  // flat: less than 0.001 grey level in all
    for (float& x : v) x = float(x / norm);
    return v;
}

std::vector<double> PointFilter::distances(const Frame8& observed) const {
    const std::vector<float> o = prepare(observed, observed_bg_);
    std::vector<double> d(renders_.size(), std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < renders_.size(); ++i)
        for (const std::vector<float>& r : renders_[i]) {
            double ncc = 0;
            if (!o.empty() && !r.empty())
                for (size_t k = 0; k < o.size(); ++k) ncc += double(o[k]) * double(r[k]);
            d[i] = std::min(d[i], 1.0 - ncc);
        }
    return d;
}

std::vector<int> PointFilter::ranking(const Frame8& observed) const {
    const std::vector<double> d = distances(observed);
    std::vector<int> order(d.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d[size_t(a)] < d[size_t(b)]; });
    return order;
}

}  // namespace vtloc::sim
