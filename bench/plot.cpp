// vtloc-bench --plot: latency over N and the per-stage breakdown, drawn with
// OpenCV (Hershey fonts: no font files needed).
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/report.h"
#include "bench/stages.h"
#include "base/error.h"
#include "engine/io/image_mat.h"

namespace vtloc::bench {

using nlohmann::json;

namespace {

const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kGpu(200, 110, 30), kCpu(40, 90, 220), kStep(60, 160, 60);
const std::vector<cv::Scalar> kStageColours{{180, 119, 31}, {14, 127, 255}, {44, 160, 44},
                                            {40, 39, 214}, {189, 103, 148}, {75, 86, 140}, {160, 160, 160}};

void text(cv::Mat& m, const std::string& s, cv::Point at, double scale = 0.45, cv::Scalar c = kInk, int thick = 1) {
    cv::putText(m, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, c, thick, cv::LINE_AA);
}

std::string fmt(double v) {
    char b[32];
    if (v == 0) return "0";
    std::snprintf(b, sizeof b, v >= 100 ? "%.0f" : v >= 10 ? "%.1f" : v >= 1 ? "%.2f" : "%.3f", v);
    return b;
}

// A "nice" tick step for a range.
double tick_step(double range) {
    const double raw = range / 5, mag = std::pow(10, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (raw <= m * mag) return m * mag;
    return 10 * mag;
}

struct Series {
    std::string label;
    cv::Scalar colour;
    std::vector<cv::Point2d> pts;
};

// A line chart of y over N in `box`, y from 0.
void line_chart(cv::Mat& m, cv::Rect box, const std::string& title, const std::string& ylabel,
                const std::vector<Series>& series) {
    double xmax = 1, ymax = 0;
    for (const Series& s : series)
        for (auto& p : s.pts) xmax = std::max(xmax, p.x), ymax = std::max(ymax, p.y);
    if (ymax <= 0) ymax = 1;
    const double ystep = tick_step(ymax * 1.1), ytop = std::ceil(ymax * 1.1 / ystep) * ystep;
    const cv::Rect plot(box.x + 60, box.y + 30, box.width - 80, box.height - 75);
    auto at = [&](cv::Point2d p) {
        return cv::Point(int(plot.x + p.x / xmax * plot.width), int(plot.y + plot.height - p.y / ytop * plot.height));
    };
    text(m, title + " (" + ylabel + ")", {box.x + 10, box.y + 18}, 0.55, kInk, 1);
    for (double y = 0; y <= ytop + 1e-9; y += ystep) {
        cv::Point a = at({0, y}), b = at({xmax, y});
        cv::line(m, a, b, kGrid, 1);
        text(m, fmt(y), {plot.x - 55, a.y + 4}, 0.4);
    }
    const double xstep = xmax >= 32 ? 16 : xmax >= 8 ? 4 : 1;
    for (double x = 0; x <= xmax + 1e-9; x += xstep) {
        cv::Point a = at({x, 0});
        cv::line(m, a, a + cv::Point(0, 5), kInk, 1);
        text(m, std::to_string(int(x)), {a.x - 6, a.y + 20}, 0.4);
    }
    cv::rectangle(m, plot, kInk, 1);
    text(m, "ILU iterations N", {plot.x + plot.width / 2 - 60, plot.y + plot.height + 40}, 0.45);
    int ly = plot.y + 18;
    for (const Series& s : series) {
        for (size_t i = 0; i + 1 < s.pts.size(); ++i) cv::line(m, at(s.pts[i]), at(s.pts[i + 1]), s.colour, 2, cv::LINE_AA);
        for (auto& p : s.pts) cv::circle(m, at(p), 4, s.colour, cv::FILLED, cv::LINE_AA);
        cv::line(m, {plot.x + 10, ly - 4}, {plot.x + 35, ly - 4}, s.colour, 2);
        text(m, s.label, {plot.x + 42, ly}, 0.42);
        ly += 18;
    }
}

// One 100% bar per backend split into stages, ms written beside.
void stage_bars(cv::Mat& m, cv::Rect box, const json& r) {
    text(m, "Per-stage time (median of profiled runs; share of the node sum)", {box.x + 10, box.y + 18}, 0.55);
    std::vector<std::string> names = stage_names();
    names.push_back("other");
    int y = box.y + 45;
    for (const char* b : {"gpu", "cpu"}) {
        if (!r.contains(b)) continue;
        const json& st = r[b]["stages_ms"];
        const double total = st["total"]["median"].get<double>();
        text(m, std::string(b == std::string("gpu") ? "GPU" : "CPU ref") + "  " + fmt(total) + " ms", {box.x + 10, y + 22}, 0.5);
        const int x0 = box.x + 170, w = box.width - 190, h = 34;
        double acc = 0;
        for (size_t i = 0; i < names.size(); ++i) {
            if (!st.contains(names[i]) || total <= 0) continue;
            const double v = st[names[i]]["median"].get<double>();
            const int a = x0 + int(acc / total * w), e = x0 + int((acc + v) / total * w);
            cv::rectangle(m, cv::Rect(a, y, std::max(e - a, 1), h), kStageColours[i], cv::FILLED);
            if (e - a > 60) text(m, fmt(v), {a + 4, y + 22}, 0.42, cv::Scalar(255, 255, 255));
            acc += v;
        }
        y += h + 16;
    }
    int x = box.x + 170;
    for (size_t i = 0; i < names.size(); ++i) {
        cv::rectangle(m, cv::Rect(x, y + 4, 14, 14), kStageColours[i], cv::FILLED);
        text(m, names[i], {x + 18, y + 16}, 0.42);
        x += 30 + int(names[i].size()) * 9;
    }
}

}  // namespace

void draw_plot(const json& r, const std::string& path) {
    cv::Mat m(660, 1200, CV_8UC3, cv::Scalar(255, 255, 255));
    const std::string title = "vtloc-bench  " + r["device"]["name"].get<std::string>() + "  |  " +
                              r["model"]["config_name"].get<std::string>() + "  |  " + r["date"].get<std::string>();
    text(m, title, {15, 28}, 0.6, kInk, 1);
    std::vector<Series> e2e, node;
    for (const char* b : {"gpu", "cpu"}) {
        if (!r.contains(b) || !r[b].contains("ilu")) continue;
        const cv::Scalar c = b == std::string("gpu") ? kGpu : kCpu;
        Series s{std::string(b) + " end to end (wall)", c, {}}, n{std::string(b) + " ILU node", c, {}};
        for (const json& row : r[b]["ilu"]["table"]) {
            s.pts.push_back({row["n"].get<double>(), row["end_to_end_ms"]["median"].get<double>()});
            n.pts.push_back({row["n"].get<double>(), row["ilu_gpu_ms"].get<double>()});
        }
        e2e.push_back(s);
        if (b == std::string("gpu")) {
            node.push_back(n);
            const json& st = r[b]["ilu"].value("stepped", json());
            if (st.is_object() && st["step_ms"].is_array() && !st["step_ms"].empty()) {
                Series cum{"gpu one dispatch per iteration (cumulative)", kStep, {{0, 0}}};
                double acc = 0;
                for (size_t k = 0; k < st["step_ms"].size(); ++k)
                    cum.pts.push_back({double(k + 1), acc += st["step_ms"][k].get<double>()});
                node.push_back(cum);
            }
        }
    }
    if (e2e.empty()) text(m, "no ILU sweep in this report (MCR head or --iters empty)", {40, 200}, 0.6);
    else {
        line_chart(m, {0, 45, 600, 400}, "Latency over N", "ms", e2e);
        line_chart(m, {600, 45, 600, 400}, "ILU head on the GPU over N", "ms", node);
    }
    stage_bars(m, {0, 470, 1200, 240}, r);
    io::write_png(path, m);
}

}  // namespace vtloc::bench
