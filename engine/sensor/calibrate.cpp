// Fitting a Taxim-style table to ball presses. Each pixel of a press is a
// sample: its gel slope (from the ball's known shape) picks a table bin, its
// colour change against the smoothed empty frame is the target. A bin's
// quadratic is a least-squares fit over the bins around it, widened until
// there are enough samples: real presses reach most slopes but leave many
// (magnitude, direction) bins with a pixel or none.
#include "engine/sensor/calibrate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/safetensors.h"
#include "engine/sensor/ball_press.h"
#include "engine/sensor/gel_shading.h"

namespace vtloc::sensor {

namespace {

constexpr int kF = 6;  // u^2, v^2, uv, u, v, 1

// A bin's sufficient statistics: A = sum phi phi^T, B = sum phi t^T, n.
struct Stats {
    std::array<double, kF * kF> A{};
    std::array<double, kF * 3> B{};
    double n = 0;
    void add(const Stats& o, double sign) {
        for (int i = 0; i < kF * kF; ++i) A[i] += sign * o.A[i];
        for (int i = 0; i < kF * 3; ++i) B[i] += sign * o.B[i];
        n += sign * o.n;
    }
};

// Solves (A + ridge on the position terms) x = B for three right-hand sides; false if singular.
bool solve(Stats s, double ridge, std::array<double, kF * 3>& x) {
    for (int i = 0; i < kF - 1; ++i) s.A[i * kF + i] += ridge;
    for (int col = 0; col < kF; ++col) {
        int piv = col;
        for (int r = col + 1; r < kF; ++r)
            if (std::abs(s.A[r * kF + col]) > std::abs(s.A[piv * kF + col])) piv = r;
        if (!(std::abs(s.A[piv * kF + col]) > 1e-12)) return false;
        for (int k = 0; k < kF; ++k) std::swap(s.A[col * kF + k], s.A[piv * kF + k]);
        for (int k = 0; k < 3; ++k) std::swap(s.B[col * 3 + k], s.B[piv * 3 + k]);
        for (int r = 0; r < kF; ++r) {
            if (r == col) continue;
            const double f = s.A[r * kF + col] / s.A[col * kF + col];
            for (int k = col; k < kF; ++k) s.A[r * kF + k] -= f * s.A[col * kF + k];
            for (int k = 0; k < 3; ++k) s.B[r * 3 + k] -= f * s.B[col * 3 + k];
        }
    }
    for (int i = 0; i < kF; ++i)
        for (int k = 0; k < 3; ++k) x[i * 3 + k] = s.B[i * 3 + k] / s.A[i * kF + i];
    return true;
}

void check_press(const BallPress& p, size_t i, int H, int W) {
    const std::string who = "calibrate: press " + std::to_string(i);
    if (p.frame.size() != size_t(H) * size_t(W) * 3)
        throw Error(who + ": the frame is not " + std::to_string(W) + "x" + std::to_string(H) + " RGB like the empty frame");
    if (!(p.cx >= 0 && p.cx < W && p.cy >= 0 && p.cy < H))
        throw Error(who + ": the contact's centre (" + std::to_string(p.cx) + ", " + std::to_string(p.cy) + ") is off the frame");
    if (!(p.radius_px > 0 && p.radius_px < std::max(H, W)))
        throw Error(who + ": the contact's radius " + std::to_string(p.radius_px) + " px is not in (0, frame size)");
}

}  // namespace

std::vector<float> press_height_px(const BallPress& p, int H, int W, const CalibrateOptions& o) {
    std::vector<float> ind = ball_indentation_mm(H, W, o.mm_per_px, p.cx, p.cy, p.radius_px, o.ball_radius_mm);
    if (o.drape) drape_gel(ind, H, W, o.mm_per_px, default_drape_sigmas_mm());
    for (float& v : ind) v = float(double(v) / o.mm_per_px);
    return ind;
}

Calibration fit_calibration(const std::vector<BallPress>& presses, const std::vector<uint8_t>& empty, int H, int W,
                            const CalibrateOptions& o) {
    if (presses.empty()) throw Error("calibrate: no ball presses to fit");
    if (H < 8 || W < 8 || empty.size() != size_t(H) * size_t(W) * 3)
        throw Error("calibrate: the empty frame must be W x H RGB, at least 8 x 8");
    if (!(o.ball_radius_mm > 0) || !(o.mm_per_px > 0) || o.bins < 3 || o.bins > 4096 || o.min_samples < kF ||
        !(o.ridge >= 0) || o.flat_stride < 1 || !(o.background_sigma_px >= 0))
        throw Error("calibrate: options out of range (ball radius and mm per pixel > 0, 3 <= bins <= 4096, min samples >= 6)");
    for (size_t i = 0; i < presses.size(); ++i) check_press(presses[i], i, H, W);

    Calibration c;
    c.height = H, c.width = W, c.mm_per_px = o.mm_per_px, c.bins = o.bins;
    cv::Mat bg(H, W, CV_32FC3);
    for (size_t i = 0; i < empty.size(); ++i) reinterpret_cast<float*>(bg.data)[i] = empty[i];
    if (o.background_sigma_px > 0)
        cv::GaussianBlur(bg, bg, cv::Size(0, 0), o.background_sigma_px, o.background_sigma_px, cv::BORDER_REPLICATE);
    c.real_bg.assign(reinterpret_cast<float*>(bg.data), reinterpret_cast<float*>(bg.data) + empty.size());
    c.depth_bg.assign(size_t(H) * size_t(W), 0.0f);

    // Statistics per bin. Direction bins are periodic with period bins - 1 (the
    // last is reached only at exactly +pi, the same slope as bin 0's -pi).
    const int B = o.bins, P = B - 1;
    const double x0 = 0.5 * (W - 1), y0 = 0.5 * (H - 1), s = 0.5 * std::max(H, W);
    std::vector<Stats> bin(size_t(B) * size_t(P));
    for (const BallPress& p : presses) {
        const std::vector<float> h = press_height_px(p, H, W, o);
        for (int r = 0; r < H; ++r)
            for (int col = 0; col < W; ++col) {
                const auto [gr, gc] = height_gradient(h, H, W, r, col);
                auto [m, d] = table_bin(gr, gc, B);
                if (m == 0 && (r % o.flat_stride || col % o.flat_stride)) continue;
                d %= P;
                const double u = (col - x0) / s, v = (r - y0) / s, phi[kF] = {u * u, v * v, u * v, u, v, 1};
                const size_t px = (size_t(r) * size_t(W) + size_t(col)) * 3;
                Stats& st = bin[size_t(m) * size_t(P) + size_t(d)];
                for (int a = 0; a < kF; ++a) {
                    for (int b = 0; b < kF; ++b) st.A[a * kF + b] += phi[a] * phi[b];
                    for (int ch = 0; ch < 3; ++ch) st.B[a * 3 + ch] += phi[a] * (double(p.frame[px + ch]) - c.real_bg[px + ch]);
                }
                st.n += 1;
            }
    }
    // Prefix sums over magnitude and three periods of direction, so a window
    // that wraps around is one rectangle.
    const int D3 = 3 * P;
    std::vector<Stats> pre(size_t(B + 1) * size_t(D3 + 1));
    auto at = [&](int m, int d) -> Stats& { return pre[size_t(m) * size_t(D3 + 1) + size_t(d)]; };
    for (int m = 1; m <= B; ++m)
        for (int d = 1; d <= D3; ++d) {
            Stats& q = at(m, d);
            q = bin[size_t(m - 1) * size_t(P) + size_t((d - 1) % P)];
            q.add(at(m - 1, d), 1), q.add(at(m, d - 1), 1), q.add(at(m - 1, d - 1), -1);
        }
    auto window = [&](int m, int d, int k) {  // bins [m-k, m+k] x [d-k, d+k] (mod P), clipped in m
        const int m0 = std::max(0, m - k), m1 = std::min(B - 1, m + k);
        int d0 = P + d - k, d1 = P + d + k;
        if (d1 - d0 + 1 >= P) d0 = P, d1 = 2 * P - 1;
        Stats w = at(m1 + 1, d1 + 1);
        w.add(at(m0, d1 + 1), -1), w.add(at(m1 + 1, d0), -1), w.add(at(m0, d0), 1);
        return w;
    };
    const double total = window(0, 0, B).n;
    for (int ch = 0; ch < 3; ++ch) c.poly[ch].assign(size_t(B) * size_t(B) * kF, 0.0f);
    for (int m = 0; m < B; ++m)
        for (int d = 0; d < B; ++d) {
            std::array<double, kF * 3> x{};
            for (int k = 0;; ++k) {
                const Stats w = window(m, d % P, k);
                const bool all = k >= B;
                if ((w.n >= o.min_samples || w.n >= total || all) && (solve(w, o.ridge, x) || all)) break;
            }
            // Back from (u, v) to the table's pixel basis [x^2, y^2, xy, x, y, 1].
            for (int ch = 0; ch < 3; ++ch) {
                const double a = x[0 * 3 + ch] / (s * s), b = x[1 * 3 + ch] / (s * s), e = x[2 * 3 + ch] / (s * s);
                const double f = x[3 * 3 + ch] / s, g = x[4 * 3 + ch] / s, k0 = x[5 * 3 + ch];
                const double coef[kF] = {a, b, e, f - 2 * a * x0 - e * y0, g - 2 * b * y0 - e * x0,
                                         k0 + a * x0 * x0 + b * y0 * y0 + e * x0 * y0 - f * x0 - g * y0};
                float* out = &c.poly[ch][(size_t(m) * size_t(B) + size_t(d)) * kF];
                for (int i = 0; i < kF; ++i) out[i] = float(coef[i]);
            }
        }
    c.press_f0 = empty;
    c.n_press = int(presses.size());
    for (const BallPress& p : presses) {
        c.press_imgs.insert(c.press_imgs.end(), p.frame.begin(), p.frame.end());
        c.press_center.push_back(float(p.cx)), c.press_center.push_back(float(p.cy));
        c.press_radius.push_back(std::max(1, int(std::lround(p.radius_px))));
    }
    return c;
}

namespace {

// The residual with the table's shader built once by the caller (2 MB of
// tables: refine_circle scores ~40 circles per press).
PressResidual residual_with(const Calibration& c, const GelShader& shader, const BallPress& p, const CalibrateOptions& o) {
    const int H = c.height, W = c.width;
    CalibrateOptions q = o;
    q.mm_per_px = c.mm_per_px;
    std::vector<float> h = press_height_px(p, H, W, q), shade;
    for (size_t i = 0; i < h.size(); ++i) h[i] += c.depth_bg[i];
    shader.shade(h, shade);
    PressResidual res;
    double nin = 0, nout = 0;
    for (int r = 0; r < H; ++r)
        for (int col = 0; col < W; ++col) {
            const size_t px = (size_t(r) * size_t(W) + size_t(col)) * 3;
            double d = 0;
            for (int ch = 0; ch < 3; ++ch)
                d += std::abs(std::clamp(double(shade[px + ch]) + c.real_bg[px + ch], 0.0, 255.0) - double(p.frame[px + ch]));
            const bool inside = std::hypot(col - p.cx, r - p.cy) <= p.radius_px;
            (inside ? res.inside : res.outside) += d / 3;
            (inside ? nin : nout) += 1;
        }
    res.inside = nin > 0 ? res.inside / nin : 0;
    res.outside = nout > 0 ? res.outside / nout : 0;
    return res;
}

}  // namespace

PressResidual press_residual(const Calibration& c, const BallPress& p, const CalibrateOptions& o) {
    check_press(p, 0, c.height, c.width);
    return residual_with(c, GelShader(c), p, o);
}

BallPress detected_circle(BallPress p, const std::vector<uint8_t>& empty, int H, int W, const std::string& name) {
    const DetectedContact d = detect_contact(p.frame, empty, H, W);
    if (!d.found) throw Error("calibrate: " + name + ": no contact found (the frame equals the empty frame)");
    p.cx = d.cx, p.cy = d.cy, p.radius_px = d.radius;
    return p;
}

BallPress refine_circle(const Calibration& c, BallPress p, const CalibrateOptions& o) {
    check_press(p, 0, c.height, c.width);
    const GelShader shader(c);
    auto cost = [&](const BallPress& q) {
        if (!(q.radius_px > 1 && q.cx >= 0 && q.cx < c.width && q.cy >= 0 && q.cy < c.height)) return HUGE_VAL;
        const PressResidual r = residual_with(c, shader, q, o);
        const double area = M_PI * q.radius_px * q.radius_px, all = double(c.height) * c.width;
        return (r.inside * area + r.outside * (all - area)) / all;
    };
    double best = cost(p);
    for (double step : {2.0, 1.0, 0.5})
        for (bool moved = true; moved;) {
            moved = false;
            for (int k = 0; k < 3; ++k)
                for (double sign : {-1.0, 1.0}) {
                    BallPress q = p;
                    (k == 0 ? q.cx : k == 1 ? q.cy : q.radius_px) += sign * step;
                    const double v = cost(q);
                    if (v < best) best = v, p = std::move(q), moved = true;
                }
        }
    return p;
}

CalibrateRun calibrate(std::vector<BallPress> presses, const std::vector<uint8_t>& empty, int H, int W,
                       const CalibrateOptions& o, int max_rounds) {
    std::vector<size_t> detected;
    for (size_t i = 0; i < presses.size(); ++i) {
        BallPress& p = presses[i];
        if (p.radius_px != 0) continue;
        if (p.frame.size() == size_t(H) * size_t(W) * 3 && empty.size() == p.frame.size())
            p = detected_circle(std::move(p), empty, H, W, "press " + std::to_string(i));
        detected.push_back(i);
    }
    CalibrateRun run;
    run.calib = fit_calibration(presses, empty, H, W, o);
    while (!detected.empty() && run.rounds < max_rounds) {
        std::vector<double> moves;
        for (size_t i : detected) {
            const BallPress q = refine_circle(run.calib, presses[i], o);
            moves.push_back(std::max({std::abs(q.cx - presses[i].cx), std::abs(q.cy - presses[i].cy),
                                      std::abs(q.radius_px - presses[i].radius_px)}));
            presses[i] = q;
        }
        std::nth_element(moves.begin(), moves.begin() + ptrdiff_t(moves.size() / 2), moves.end());
        run.last_move_px = moves[moves.size() / 2];
        run.calib = fit_calibration(presses, empty, H, W, o);
        ++run.rounds;
        if (run.last_move_px < 0.25) break;
    }
    run.presses = std::move(presses);
    return run;
}

void save_calibration(const std::string& path, const Calibration& c) {
    const int64_t H = c.height, W = c.width, B = c.bins, N = c.n_press;
    std::vector<TensorBlob> t;
    const char* names[3] = {"poly_r", "poly_g", "poly_b"};
    for (int ch = 0; ch < 3; ++ch) t.push_back(TensorBlob::f32(names[ch], {B, B, 6}, c.poly[ch]));
    t.push_back(TensorBlob::f32("real_bg", {H, W, 3}, c.real_bg));
    t.push_back(TensorBlob::f32("depth_bg", {H, W}, c.depth_bg));
    if (N > 0) {
        t.push_back(TensorBlob{"press_f0", DType::U8, {H, W, 3}, c.press_f0});
        t.push_back(TensorBlob{"press_imgs", DType::U8, {N, H, W, 3}, c.press_imgs});
        t.push_back(TensorBlob::f32("press_center", {N, 2}, c.press_center));
        t.push_back(TensorBlob::i32("press_radius", {N}, c.press_radius));
    }
    char pix[64];
    std::snprintf(pix, sizeof pix, "pixmm=%.9g", c.mm_per_px);
    write_safetensors(path, t, {{"sensor", pix}, {"producer", "vtloc calibrate"}});
}

std::vector<BallPress> calibration_presses(const Calibration& c) {
    const size_t bytes = size_t(c.height) * size_t(c.width) * 3;
    std::vector<BallPress> out;
    for (int i = 0; i < c.n_press; ++i) {
        BallPress p;
        p.frame.assign(c.press_imgs.begin() + ptrdiff_t(i * bytes), c.press_imgs.begin() + ptrdiff_t((i + 1) * bytes));
        p.cx = c.press_center[size_t(i) * 2], p.cy = c.press_center[size_t(i) * 2 + 1];
        p.radius_px = c.press_radius[size_t(i)];
        out.push_back(std::move(p));
    }
    return out;
}

}  // namespace vtloc::sensor
