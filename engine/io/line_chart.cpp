#include "engine/io/line_chart.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/io/image_mat.h"

namespace vtloc::io {

namespace {

const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225);
// BGR, distinguishable in colour and in grey; past the last, the colours repeat with another marker.
const cv::Scalar kColours[] = {{180, 90, 30}, {40, 40, 200}, {60, 160, 60}, {170, 60, 160},
                               {0, 140, 230}, {120, 120, 120}, {200, 170, 40}, {40, 100, 120},
                               {150, 100, 240}, {40, 150, 150}, {60, 210, 150}, {110, 30, 20}};
constexpr size_t kPalette = sizeof kColours / sizeof kColours[0];
constexpr double kLegendScale = 0.42;

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale = 0.5, int align = 0) {
    int base = 0;
    const cv::Size sz = cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
    if (align == 1) at.x -= sz.width / 2;
    if (align == 2) at.x -= sz.width;
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, kInk, 1, cv::LINE_AA);
}

void dashed_line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& c) {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const int n = std::max(1, int(len / 8));
    for (int i = 0; i < n; i += 2)
        cv::line(img, a + (b - a) * (double(i) / n), a + (b - a) * (double(i + 1) / n), c, 2, cv::LINE_AA);
}

// A filled circle, square or diamond: the palette's first, second and third round.
void marker(cv::Mat& img, cv::Point2d p, size_t shape, const cv::Scalar& c) {
    const cv::Point q(int(std::lround(p.x)), int(std::lround(p.y)));
    if (shape % 3 == 0) cv::circle(img, q, 4, c, cv::FILLED, cv::LINE_AA);
    else if (shape % 3 == 1) cv::rectangle(img, q - cv::Point(4, 4), q + cv::Point(4, 4), c, cv::FILLED);
    else {
        const cv::Point d[] = {q + cv::Point(0, -5), q + cv::Point(5, 0), q + cv::Point(0, 5), q + cv::Point(-5, 0)};
        cv::fillConvexPoly(img, d, 4, c, cv::LINE_AA);
    }
}

int text_width(const std::string& s, double scale) {
    int base = 0;
    return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base).width;
}

// The label cut to `room` pixels, ending in "..." where it was cut.
std::string fit(const std::string& s, int room) {
    if (text_width(s, kLegendScale) <= room) return s;
    std::string t = s;
    while (!t.empty() && text_width(t + "...", kLegendScale) > room) t.pop_back();
    return t + "...";
}

}  // namespace

void save_line_chart_png(const std::string& path, const LineChart& c) {
    if (c.x.empty() || c.series.empty()) throw Error(path + ": a chart needs x values and at least one series");
    double y_max = 0;
    for (const ChartSeries& s : c.series) {
        if (s.y.size() != c.x.size()) throw Error(path + ": series '" + s.name + "' has " + std::to_string(s.y.size()) + " values for " + std::to_string(c.x.size()) + " x");
        for (double v : s.y)
            if (std::isfinite(v)) y_max = std::max(y_max, v);
    }
    // A round top: 1, 2 or 5 times a power of ten, in five steps.
    const double raw = std::max(y_max, 1e-9) / 5, mag = std::pow(10, std::floor(std::log10(raw)));
    const double step = raw <= mag ? mag : raw <= 2 * mag ? 2 * mag : raw <= 5 * mag ? 5 * mag : 10 * mag, top = 5 * step;
    const double x_lo = *std::min_element(c.x.begin(), c.x.end()), x_hi = *std::max_element(c.x.begin(), c.x.end());
    cv::Mat img(c.height, c.width, CV_8UC3, cv::Scalar(255, 255, 255));
    // The legend as wide as its longest label, up to half the chart; its rows as tall as fit.
    int label_w = 0;
    for (const ChartSeries& s : c.series) label_w = std::max(label_w, text_width(s.name, kLegendScale));
    const int legend_w = std::clamp(label_w + 70, 160, c.width / 2);
    const int L = 80, R = c.width - legend_w, T = 60, B = c.height - 60;
    const int row_h = std::clamp((c.height - T - 20) / int(c.series.size()), 8, 22);
    auto px = [&](double x) { return L + (x_hi > x_lo ? (x - x_lo) / (x_hi - x_lo) : 0.5) * (R - L); };
    auto py = [&](double y) { return B - y / top * (B - T); };
    char buf[32];
    for (int i = 0; i <= 5; ++i) {
        const double y = py(i * step);
        cv::line(img, cv::Point(L, int(y)), cv::Point(R, int(y)), kGrid, 1);
        std::snprintf(buf, sizeof buf, "%g", i * step);
        text(img, buf, cv::Point(L - 8, int(y) + 5), 0.45, 2);
    }
    for (double x : c.x) {
        cv::line(img, cv::Point(int(px(x)), B), cv::Point(int(px(x)), B + 5), kInk, 1);
        std::snprintf(buf, sizeof buf, "%g", x);
        text(img, buf, cv::Point(int(px(x)), B + 22), 0.45, 1);
    }
    cv::rectangle(img, cv::Point(L, T), cv::Point(R, B), kInk, 1);
    text(img, c.title, cv::Point(8, 26), 0.6);
    text(img, c.x_label, cv::Point((L + R) / 2, c.height - 18), 0.5, 1);
    text(img, c.y_label, cv::Point(L, T - 10), 0.5, 1);
    for (size_t k = 0; k < c.series.size(); ++k) {
        const ChartSeries& s = c.series[k];
        const size_t pick = s.colour >= 0 ? size_t(s.colour) : k;
        const cv::Scalar col = kColours[pick % kPalette];
        const size_t shape = pick / kPalette;
        for (size_t i = 0; i < c.x.size(); ++i) {
            if (!std::isfinite(s.y[i])) continue;
            const cv::Point2d p(px(c.x[i]), py(s.y[i]));
            marker(img, p, shape, col);
            if (i + 1 < c.x.size() && std::isfinite(s.y[i + 1])) {
                const cv::Point2d q(px(c.x[i + 1]), py(s.y[i + 1]));
                if (s.dashed) dashed_line(img, p, q, col);
                else cv::line(img, p, q, col, 2, cv::LINE_AA);
            }
        }
        const int ly = T + 10 + int(k) * row_h;
        if (s.dashed) dashed_line(img, cv::Point2d(R + 15, ly), cv::Point2d(R + 45, ly), col);
        else cv::line(img, cv::Point(R + 15, ly), cv::Point(R + 45, ly), col, 2, cv::LINE_AA);
        marker(img, cv::Point2d(R + 30, ly), shape, col);
        text(img, fit(s.name, c.width - R - 60), cv::Point(R + 52, ly + 5), kLegendScale);
    }
    write_png(path, img);
}

}  // namespace vtloc::io
