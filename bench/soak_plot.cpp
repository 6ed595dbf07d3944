#include "bench/soak_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/io/image_mat.h"

namespace vtloc::bench {

namespace {

const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kLine(200, 110, 30), kFit(40, 90, 220);

void text(cv::Mat& m, const std::string& s, cv::Point at, double scale = 0.45) {
    cv::putText(m, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, kInk, 1, cv::LINE_AA);
}

// One panel: y after the warm-up over the run index, in the rectangle r, on
// the data's own range widened to at least 1 MiB (so a flat line looks flat
// and the 1 MiB drift budget is visible against it).
void panel(cv::Mat& m, cv::Rect r, const std::vector<double>& y, size_t from, const std::string& title, double slope) {
    double lo = *std::min_element(y.begin() + long(from), y.end()), hi = *std::max_element(y.begin() + long(from), y.end());
    if (hi - lo < 1) {
        const double mid = 0.5 * (lo + hi);
        lo = mid - 0.5, hi = mid + 0.5;
    }
    const double x0 = double(from), n = std::max(double(y.size() - 1) - x0, 1.0);
    auto px = [&](double i, double v) {
        return cv::Point(r.x + int(std::lround((i - x0) / n * r.width)),
                         r.y + r.height - int(std::lround((v - lo) / (hi - lo) * r.height)));
    };
    for (int k = 0; k <= 4; ++k) {
        const double v = lo + (hi - lo) * k / 4;
        cv::line(m, px(x0, v), px(x0 + n, v), kGrid);
        char b[32];
        std::snprintf(b, sizeof b, "%.2f", v);
        text(m, b, {r.x - 62, px(x0, v).y + 4}, 0.4);
    }
    for (int k = 0; k <= 4; ++k) {
        char b[32];
        std::snprintf(b, sizeof b, "%.0f", x0 + n * k / 4);
        text(m, b, {px(x0 + n * k / 4, lo).x - 12, r.y + r.height + 16}, 0.4);
    }
    for (size_t i = from + 1; i < y.size(); ++i)
        cv::line(m, px(double(i - 1), y[i - 1]), px(double(i), y[i]), kLine, 1, cv::LINE_AA);
    if (slope != 0) {
        double mean = 0, mx = 0;
        for (size_t i = from; i < y.size(); ++i) mean += y[i], mx += double(i);
        mean /= double(y.size() - from), mx /= double(y.size() - from);
        cv::line(m, px(x0, mean + slope * (x0 - mx)), px(x0 + n, mean + slope * (x0 + n - mx)), kFit, 1, cv::LINE_AA);
    }
    cv::rectangle(m, r, kInk);
    text(m, title, {r.x, r.y - 8}, 0.45);
}

}  // namespace

void plot_soak(const std::string& path, const std::vector<double>& rss, const std::vector<double>& gpu, size_t warmup,
               double slope) {
    if (rss.empty() || rss.size() != gpu.size()) throw Error(path + ": no soak samples to plot");
    const size_t from = warmup + 1 < rss.size() ? warmup : 0;
    cv::Mat m(580, 900, CV_8UC3, cv::Scalar(255, 255, 255));
    char t[200];
    std::snprintf(t, sizeof t, "host RSS (MiB) after the warm-up (%.0f -> %.0f MiB in runs 0..%zu); red: fit, %.3g MiB/1000 runs",
                  rss.front(), rss[from], from, 1000 * slope);
    panel(m, {80, 40, 790, 200}, rss, from, t, slope);
    std::snprintf(t, sizeof t, "GPU memory held by the context (MiB) after the warm-up (%.0f -> %.0f MiB)", gpu.front(), gpu[from]);
    panel(m, {80, 320, 790, 200}, gpu, from, t, 0);
    text(m, "run", {460, 565});
    io::write_png(path, m);
}

}  // namespace vtloc::bench
