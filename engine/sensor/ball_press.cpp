#include "engine/sensor/ball_press.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

namespace vtloc::sensor {

DetectedContact detect_contact(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, int H, int W) {
    DetectedContact d;
    const size_t n = size_t(H) * W;
    if (frame.size() != n * 3 || empty.size() != n * 3) return d;
    cv::Mat diff(H, W, CV_32F);
    for (size_t i = 0; i < n; ++i) {
        float s = 0;
        for (int c = 0; c < 3; ++c) s += std::abs(float(frame[i * 3 + c]) - float(empty[i * 3 + c]));
        diff.at<float>(int(i / W), int(i % W)) = s;
    }
    cv::GaussianBlur(diff, diff, cv::Size(0, 0), 1.5, 1.5, cv::BORDER_REFLECT);
    double mx = 0;
    cv::minMaxLoc(diff, nullptr, &mx);
    if (!(mx > 0)) return d;
    cv::Mat mask = diff > kContactFraction * mx;
    cv::Mat labels, stats, centroids;
    int k = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
    int best = 0, best_area = 0;
    for (int l = 1; l < k; ++l)
        if (stats.at<int>(l, cv::CC_STAT_AREA) > best_area) best = l, best_area = stats.at<int>(l, cv::CC_STAT_AREA);
    if (best == 0) return d;
    d.found = true;
    d.cx = centroids.at<double>(best, 0);
    d.cy = centroids.at<double>(best, 1);
    d.radius = std::sqrt(best_area / M_PI);
    return d;
}

BallCap ball_cap(double r, double ball) {
    BallCap b;
    b.sphere_mm = std::max(ball, 1.05 * r);
    b.depth_mm = b.sphere_mm - std::sqrt(b.sphere_mm * b.sphere_mm - r * r);
    return b;
}

std::vector<float> ball_indentation_mm(int H, int W, double mm_per_px, double cx, double cy, double contact_radius_px,
                                       double ball_radius_mm) {
    const double a = contact_radius_px * mm_per_px;
    const BallCap cap = ball_cap(a, ball_radius_mm);
    const double R2 = cap.sphere_mm * cap.sphere_mm, rim = std::sqrt(R2 - a * a);
    std::vector<float> ind(size_t(H) * size_t(W), 0.0f);
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            const double u = (c - cx) * mm_per_px, v = (r - cy) * mm_per_px, rho2 = u * u + v * v;
            if (rho2 < a * a) ind[size_t(r) * size_t(W) + size_t(c)] = float(std::sqrt(R2 - rho2) - rim);
        }
    return ind;
}

}  // namespace vtloc::sensor
