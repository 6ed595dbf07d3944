// The contact mask's plain C++ reference (engine/ops/gel_mask.h, op gel_contact_mask's) against
// the OpenCV pipeline it replaced, kept here as the oracle: equal 0/1 masks on the 49 real ball
// presses and on random slopes, sizes and radii.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

#include "engine/sensor/calibration.h"
#include "engine/sensor/gel_shape.h"

using namespace vtloc;
using namespace vtloc::sensor;

namespace {

cv::Mat disc(int r) {
    cv::Mat k(2 * r + 1, 2 * r + 1, CV_8U, cv::Scalar(0));
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x) k.at<uint8_t>(y + r, x + r) = x * x + y * y <= r * r;
    return k;
}

cv::Mat fill_holes(const cv::Mat& m) {
    cv::Mat bg;
    cv::copyMakeBorder(1 - m, bg, 1, 1, 1, 1, cv::BORDER_CONSTANT, cv::Scalar(1));
    cv::floodFill(bg, cv::Point(0, 0), cv::Scalar(2), nullptr, cv::Scalar(0), cv::Scalar(0), 4);
    return cv::Mat(bg(cv::Rect(1, 1, m.cols, m.rows)) != 2) / 255;
}

cv::Mat largest_piece(const cv::Mat& m) {
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(m, labels, stats, centroids, 4, CV_32S);
    int best = 0, area = 0;
    for (int l = 1; l < n; ++l)
        if (stats.at<int>(l, cv::CC_STAT_AREA) > area) area = stats.at<int>(l, cv::CC_STAT_AREA), best = l;
    return fill_holes(best ? cv::Mat(cv::Mat(labels == best) / 255) : cv::Mat::zeros(m.size(), CV_8U));
}

// engine/sensor/gel_shape.cpp's contact_mask before the GPU op (double slopes, OpenCV's morphology).
std::vector<uint8_t> opencv_mask(const std::vector<float>& grad, int H, int W, const ShapeOptions& o) {
    cv::Mat mag(H, W, CV_64F);
    for (size_t p = 0; p < size_t(H) * size_t(W); ++p)
        mag.at<double>(int(p / size_t(W)), int(p % size_t(W))) = std::hypot(double(grad[2 * p]), double(grad[2 * p + 1]));
    cv::blur(mag, mag, cv::Size(3, 3), cv::Point(-1, -1), cv::BORDER_REPLICATE);
    cv::Mat m = mag > o.mask_threshold;
    m /= 255;
    if (o.close_radius > 0) cv::morphologyEx(m, m, cv::MORPH_CLOSE, disc(o.close_radius));
    m = fill_holes(m);
    if (o.open_radius > 0) cv::morphologyEx(m, m, cv::MORPH_OPEN, disc(o.open_radius));
    m = largest_piece(m);
    return std::vector<uint8_t>(m.datastart, m.dataend);
}

size_t count_differ(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
    size_t d = a.size() == b.size() ? 0 : std::max(a.size(), b.size());
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) d += a[i] != b[i];
    return d;
}

}  // namespace

TEST_CASE("gel shape: the contact mask equals OpenCV's on the 49 real presses", "[sensor][gel]") {
    const Calibration c = load_calibration(default_calibration_path());
    const GradientLut lut = build_gradient_lut(c);
    const int H = c.height, W = c.width;
    const size_t HW = size_t(H) * size_t(W);
    ShapeOptions no_solve;  // only the gradient is wanted here
    no_solve.sor_iterations = 0, no_solve.sor_levels = 0;
    size_t contact = 0;
    for (int i = 0; i < c.n_press; ++i) {
        INFO("press " << i);
        const std::vector<uint8_t> frame(c.press_imgs.begin() + long(i * HW * 3), c.press_imgs.begin() + long((i + 1) * HW * 3));
        const GelShape s = gel_shape(c, lut, frame, c.press_f0, no_solve);
        std::vector<float> grad(HW * 2);
        for (size_t p = 0; p < HW; ++p) grad[2 * p] = s.grad_row[p], grad[2 * p + 1] = s.grad_col[p];
        for (double threshold : {0.7, 0.5}) {
            ShapeOptions o;
            o.mask_threshold = threshold;
            const std::vector<uint8_t> m = contact_mask(grad, H, W, o);
            CHECK(count_differ(m, opencv_mask(grad, H, W, o)) == 0);
            for (uint8_t v : m) contact += v;
        }
    }
    CHECK(contact > 49 * 2 * 200);  // real contacts, not empty masks agreeing
}

TEST_CASE("gel shape: the contact mask equals OpenCV's on random slopes, sizes and radii", "[sensor][gel]") {
    std::mt19937 rng(20261201);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    size_t contact = 0;
    for (int k = 0; k < 150; ++k) {
        const int H = 1 + int(rng() % 130), W = 1 + int(rng() % 170), kind = k % 3;
        // Slopes: noise (most pixels near the threshold), or rings and blobs alone or over noise.
        std::vector<float> mag(size_t(H) * W, 0.0f), grad(size_t(H) * W * 2);
        for (int b = 1 + int(rng() % 6); b > 0; --b) {
            const float cy = float(rng() % uint32_t(H)), cx = float(rng() % uint32_t(W));
            const float rad = float(2 + rng() % 30), w = float(1 + rng() % 4);
            for (int r = 0; r < H; ++r)
                for (int col = 0; col < W; ++col)
                    if (std::abs(std::hypot(float(r) - cy, float(col) - cx) - rad) < w) mag[size_t(r) * W + size_t(col)] += 1.5f;
        }
        for (size_t p = 0; p < mag.size(); ++p) {
            const float a = 3.14159f * u(rng);
            const float m = kind == 0 ? 1.5f * std::abs(u(rng)) : mag[p] + (kind == 2 ? 0.6f * std::abs(u(rng)) : 0.0f);
            grad[2 * p] = m * std::cos(a), grad[2 * p + 1] = m * std::sin(a);
        }
        ShapeOptions o;
        o.close_radius = int(rng() % 4), o.open_radius = int(rng() % 4);
        INFO("case " << k << ": " << H << "x" << W << ", close " << o.close_radius << ", open " << o.open_radius);
        const std::vector<uint8_t> m = contact_mask(grad, H, W, o);
        CHECK(count_differ(m, opencv_mask(grad, H, W, o)) == 0);
        for (uint8_t v : m) contact += v;
    }
    CHECK(contact > 10000);
}
