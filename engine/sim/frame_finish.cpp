#include "engine/sim/frame_finish.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "engine/io/splitmix64.h"

namespace vtloc::sim::detail {

std::vector<uint8_t> finish_frame(const std::vector<float>& shading, const std::vector<float>& bg, int H, int W,
                                  const Appearance& look, uint64_t seed, bool noise) {
    const size_t n = size_t(H) * W * 3;
    std::vector<float> f(n);
    for (size_t i = 0; i < n; ++i)
        f[i] = float(look.gain[i % 3] * (double(shading[i]) + bg[i]) + look.brightness);
    if (look.blur_sigma_px > 0) {
        cv::Mat m(H, W, CV_32FC3, f.data());
        cv::GaussianBlur(m, m, cv::Size(0, 0), look.blur_sigma_px, look.blur_sigma_px, cv::BORDER_REFLECT);
    }
    if (noise && look.noise_sigma > 0) {
        // Box-Muller on SplitMix64: the same seed gives the same noise everywhere.
        io::SplitMix64 rng(seed);
        for (size_t i = 0; i < n; i += 2) {
            double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();  // u1 in (0, 1]
            double rad = std::sqrt(-2.0 * std::log(u1)) * look.noise_sigma;
            f[i] += float(rad * std::cos(2 * M_PI * u2));
            if (i + 1 < n) f[i + 1] += float(rad * std::sin(2 * M_PI * u2));
        }
    }
    std::vector<uint8_t> out(n);
    for (size_t i = 0; i < n; ++i) {
        double v = std::floor(double(f[i]) + 0.5);
        out[i] = uint8_t(std::isfinite(v) ? std::clamp(v, 0.0, 255.0) : 0.0);
    }
    return out;
}

}  // namespace vtloc::sim::detail
