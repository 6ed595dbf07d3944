// The reality check: render each real press, detect the contact in both
// frames the same way, compare.
#include "engine/sim/reality_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/io/image_mat.h"
#include "engine/sim/primitives.h"
#include "engine/sim/touch_renderer.h"

namespace vtloc::sim {

namespace {

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

cv::Mat as_mat(const std::vector<uint8_t>& v, int H, int W) {
    return cv::Mat(H, W, CV_8UC3, const_cast<uint8_t*>(v.data())).clone();
}

void write_side_by_side(const std::string& path, const Calibration& c, const RealityReport& rep,
                        const std::vector<std::vector<uint8_t>>& rendered, const RealityOptions& o) {
    const int H = c.height, W = c.width, S = 2;  // tiles drawn at twice the size, for the eye
    const int th = H * S, tw = W * S, title = 28;
    std::vector<int> rows;
    for (int i : o.png_frames)
        if (i >= 0 && i < int(rep.frames.size())) rows.push_back(i);
    if (rows.empty()) return;
    cv::Mat canvas(title + int(rows.size()) * (th + title), 3 * tw, CV_8UC3, cv::Scalar(40, 40, 40));
    const char* heads[3] = {"real", "rendered", "|rendered - real| x"};
    for (int k = 0; k < 3; ++k) {
        std::string h = heads[k];
        if (k == 2) h += std::to_string(int(o.diff_gain));
        cv::putText(canvas, h, {k * tw + 6, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.55, {255, 255, 255}, 1, cv::LINE_AA);
    }
    for (size_t r = 0; r < rows.size(); ++r) {
        const RealityFrame& f = rep.frames[rows[r]];
        const int y0 = title + int(r) * (th + title);
        cv::Mat real(H, W, CV_8UC3, const_cast<uint8_t*>(&c.press_imgs[size_t(f.index) * H * W * 3]));
        cv::Mat sim = as_mat(rendered[rows[r]], H, W), diff;
        cv::absdiff(real, sim, diff);
        diff.convertTo(diff, CV_8UC3, o.diff_gain);
        const cv::Mat* tiles[3] = {&real, &sim, &diff};
        for (int k = 0; k < 3; ++k) {
            cv::Mat big;
            cv::resize(*tiles[k], big, {tw, th}, 0, 0, cv::INTER_NEAREST);
            // Annotated circle (green) on the real and rendered tiles.
            if (k < 2)
                cv::circle(big, {int(std::lround(f.annotated_cx * S + S / 2)), int(std::lround(f.annotated_cy * S + S / 2))},
                           int(std::lround(f.annotated_r * S)), {0, 255, 0}, 1, cv::LINE_AA);
            big.copyTo(canvas(cv::Rect(k * tw, y0 + title, tw, th)));
        }
        char label[200];
        std::snprintf(label, sizeof label, "frame %d: r %.1f px, radius ratio %.2f, centres %.1f px apart, |dRGB| in %.1f out %.1f",
                      f.index, f.annotated_r, f.radius_ratio, f.centre_dist, f.drgb_inside, f.drgb_outside);
        cv::putText(canvas, label, {6, y0 + 19}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {255, 255, 255}, 1, cv::LINE_AA);
    }
    io::write_png(path, canvas);
}

// Residual offsets after the best quadratic-in-position fit (RealityReport).
void position_floor(RealityReport& rep) {
    const int n = int(rep.frames.size());
    if (n < 6) return;
    cv::Mat A(n, 6, CV_64F), b(n, 2, CV_64F);
    for (int i = 0; i < n; ++i) {
        const RealityFrame& f = rep.frames[i];
        const double x = f.annotated_cx, y = f.annotated_cy, row[6] = {x, y, x * x, y * y, x * y, 1};
        for (int k = 0; k < 6; ++k) A.at<double>(i, k) = row[k];
        b.at<double>(i, 0) = f.real.cx - f.sim.cx;
        b.at<double>(i, 1) = f.real.cy - f.sim.cy;
    }
    cv::Mat coef;
    cv::solve(A, b, coef, cv::DECOMP_SVD);
    cv::Mat r = b - A * coef;
    std::vector<double> d(n);
    for (int i = 0; i < n; ++i) d[i] = std::hypot(r.at<double>(i, 0), r.at<double>(i, 1));
    rep.floor_median_centre_dist = median(d);
    rep.floor_max_centre_dist = *std::max_element(d.begin(), d.end());
    rep.floor_frames_over_3px = int(std::count_if(d.begin(), d.end(), [](double v) { return v > 3; }));
}

// Mean |RGB difference| of the rendered and the real frame inside and outside the annotated circle.
void rgb_difference(RealityFrame& f, const std::vector<uint8_t>& sim, const std::vector<uint8_t>& real, int H, int W) {
    double in = 0, out = 0;
    size_t nin = 0, nout = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            size_t p = (size_t(y) * W + x) * 3;
            double d = 0;
            for (int k = 0; k < 3; ++k) d += std::abs(double(sim[p + k]) - double(real[p + k]));
            bool inside = std::hypot(x - f.annotated_cx, y - f.annotated_cy) <= f.annotated_r;
            (inside ? in : out) += d / 3;
            ++(inside ? nin : nout);
        }
    f.drgb_inside = nin ? in / nin : 0;
    f.drgb_outside = nout ? out / nout : 0;
}

// The report's summary over its frames, then the position floor.
void summarise(RealityReport& rep) {
    std::vector<double> rerr, cd;
    for (const RealityFrame& f : rep.frames) {
        rerr.push_back(std::abs(f.radius_ratio - 1));
        cd.push_back(f.centre_dist);
        rep.mean_drgb_inside += f.drgb_inside / rep.frames.size();
        rep.mean_drgb_outside += f.drgb_outside / rep.frames.size();
        rep.max_drgb_inside = std::max(rep.max_drgb_inside, f.drgb_inside);
        rep.max_drgb_outside = std::max(rep.max_drgb_outside, f.drgb_outside);
    }
    rep.median_radius_err = median(rerr);
    rep.max_radius_err = *std::max_element(rerr.begin(), rerr.end());
    rep.median_centre_dist = median(cd);
    rep.max_centre_dist = *std::max_element(cd.begin(), cd.end());
    position_floor(rep);
}

}  // namespace

RealityReport reality_check(const Calibration& c, const RealityOptions& o) {
    const int H = c.height, W = c.width;
    const size_t frame_bytes = size_t(H) * W * 3;
    if (c.n_press <= 0 || c.press_imgs.size() != size_t(c.n_press) * frame_bytes || c.press_f0.size() != frame_bytes ||
        c.press_center.size() != size_t(c.n_press) * 2 || c.press_radius.size() != size_t(c.n_press))
        throw Error("reality check: the calibration has no (complete) real press frames");
    if (!(o.ball_radius_mm > 0)) throw Error("reality check: ball_radius_mm must be > 0");

    Appearance look;
    look.noise_sigma = 0;
    RealityReport rep;
    std::vector<std::vector<uint8_t>> rendered;
    std::map<double, TouchRenderer> renderers;  // one ball mesh per (clamped) radius
    std::vector<uint8_t> empty_sim;
    for (int i = 0; i < c.n_press; ++i) {
        RealityFrame f;
        f.index = i;
        f.annotated_cx = c.press_center[size_t(i) * 2];
        f.annotated_cy = c.press_center[size_t(i) * 2 + 1];
        f.annotated_r = c.press_radius[i];
        // Radii at or past the ball's own are presses to its full width: the
        // sphere is enlarged to 1.05 r (README) so that d stays defined.
        const sensor::BallCap cap = sensor::ball_cap(f.annotated_r * c.mm_per_px, o.ball_radius_mm);
        const double R = cap.sphere_mm;
        f.ball_radius_mm = R;
        f.press_mm = cap.depth_mm;
        auto it = renderers.find(R);
        if (it == renderers.end()) {
            it = renderers.emplace(R, TouchRenderer(c, make_icosphere(R, o.sphere_subdivisions))).first;
            if (!o.drape_sigmas_mm.empty()) it->second.set_drape_sigmas_mm(o.drape_sigmas_mm);
        }
        const TouchRenderer& tr = it->second;
        if (empty_sim.empty()) empty_sim = tr.background_frame(look);
        // Sensor axes = world axes, looking along +z at the ball (centred on
        // the origin); the centre line is shifted so that the ball's pole
        // projects onto the annotated pixel.
        SensorPose pose;
        pose.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        pose.t = {-(f.annotated_cx - (W - 1) * 0.5) * c.mm_per_px, -(f.annotated_cy - (H - 1) * 0.5) * c.mm_per_px,
                  -10 * R};
        Touch t = tr.render_at(pose, f.press_mm, look, 0);
        if (!t.ok) throw Error(std::string("reality check: frame ") + std::to_string(i) + " did not render: " + t.reason);

        std::vector<uint8_t> real(c.press_imgs.begin() + i * frame_bytes, c.press_imgs.begin() + (i + 1) * frame_bytes);
        f.real = detect_contact(real, c.press_f0, H, W);
        f.sim = detect_contact(t.image, empty_sim, H, W);
        f.radius_ratio = f.real.radius > 0 ? f.sim.radius / f.real.radius : 0;
        f.centre_dist = std::hypot(f.sim.cx - f.real.cx, f.sim.cy - f.real.cy);
        rgb_difference(f, t.image, real, H, W);
        rep.frames.push_back(f);
        rendered.push_back(std::move(t.image));
    }
    summarise(rep);
    if (!o.png_path.empty()) write_side_by_side(o.png_path, c, rep, rendered, o);
    return rep;
}

}  // namespace vtloc::sim
