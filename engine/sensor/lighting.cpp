#include "engine/sensor/lighting.h"

#include <algorithm>
#include <cmath>

#include "base/error.h"

namespace vtloc::sensor {

namespace {

// Least squares y ~ a x + b over the pixels of `use` (channel c of the interleaved frames).
void fit_line(const std::vector<uint8_t>& f, const std::vector<uint8_t>& e, int c, const std::vector<size_t>& use, double& a, double& b) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i : use) {
        const double x = e[3 * i + size_t(c)], y = f[3 * i + size_t(c)];
        sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    const double n = double(use.size()), vx = sxx / n - (sx / n) * (sx / n);
    a = vx > 4.0 ? (sxy / n - (sx / n) * (sy / n)) / vx : 1.0;  // std < 2 levels: offset only
    if (!(a >= 0.5 && a <= 2.0)) a = 1.0;
    b = (sy - a * sx) / n;
}

}  // namespace

LightingFit fit_lighting(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, double keep) {
    if (frame.size() != empty.size() || frame.empty() || frame.size() % 3)
        throw Error("lighting: the frame and the empty frame differ in size (" + std::to_string(frame.size()) + " and " +
                    std::to_string(empty.size()) + " values)");
    const size_t P = frame.size() / 3;
    LightingFit fit;
    std::vector<size_t> all(P), use;
    for (size_t i = 0; i < P; ++i) all[i] = i;
    std::vector<std::pair<double, size_t>> r(P);
    for (int c = 0; c < 3; ++c) {
        use = all;
        double a = 1, b = 0;
        for (int round = 0; round < 4; ++round) {
            fit_line(frame, empty, c, use, a, b);
            for (size_t i = 0; i < P; ++i)
                r[i] = {std::fabs(double(frame[3 * i + size_t(c)]) - a * double(empty[3 * i + size_t(c)]) - b), i};
            const size_t k = std::max<size_t>(1, size_t(keep * double(P)));
            std::nth_element(r.begin(), r.begin() + ptrdiff_t(k - 1), r.end());
            use.resize(k);
            for (size_t j = 0; j < k; ++j) use[j] = r[j].second;
            std::sort(use.begin(), use.end());  // a fixed summation order: the same bits every run
        }
        fit_line(frame, empty, c, use, a, b);
        fit.gain[c] = a, fit.offset[c] = b;
    }
    return fit;
}

std::vector<uint8_t> match_lighting(const std::vector<uint8_t>& frame, const std::vector<uint8_t>& empty, LightingFit* out) {
    const LightingFit fit = fit_lighting(frame, empty);
    if (out) *out = fit;
    std::vector<uint8_t> m(frame.size());
    for (size_t i = 0; i < frame.size(); ++i) {
        const int c = int(i % 3);
        m[i] = uint8_t(std::clamp(std::lround((double(frame[i]) - fit.offset[c]) / fit.gain[c]), 0L, 255L));
    }
    return m;
}

}  // namespace vtloc::sensor
