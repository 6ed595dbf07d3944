// Deformation and shading: data/gelsight/README.md spells out
// the table's indexing, followed here to the letter.
#include "engine/sensor/gel_shading.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>


namespace vtloc::sensor {

void drape_gel(std::vector<float>& ind, int rows, int cols, double mm_per_px, const std::vector<double>& sigmas_mm) {
    cv::Mat z(rows, cols, CV_32F, ind.data());
    const cv::Mat original = z.clone();
    if (cv::countNonZero(original > 0) == 0) return;
    for (double s : sigmas_mm) {
        double sp = s / mm_per_px;
        if (!(sp > 0.05)) continue;  // narrower than a twentieth of a pixel: a no-op
        int k = 2 * int(std::ceil(3 * std::min(sp, double(rows + cols)))) + 1;
        // Replicate: the gel goes on beyond the grid as it is at the border.
        cv::GaussianBlur(z, z, cv::Size(k, k), sp, sp, cv::BORDER_REPLICATE);
        // Restore the contact: the gel may not sink below the object. A max,
        // not a copy of the contact region: where the blurred gel already
        // stands above the object near the contact edge (steep sides) it
        // lifts off, instead of leaving a groove along the edge (that groove
        // alone cost ~10 |dRGB| on the ring around the real contacts).
        cv::max(z, original, z);
    }
    cv::max(z, 0.0f, z);  // z aliases ind's storage
}

GelShader::GelShader(const Calibration& c) : H_(c.height), W_(c.width), bins_(c.bins) {
    poly_.resize(size_t(bins_) * bins_ * 3 * 6);
    for (int m = 0; m < bins_; ++m)
        for (int d = 0; d < bins_; ++d)
            for (int ch = 0; ch < 3; ++ch)
                for (int k = 0; k < 6; ++k)
                    poly_[((size_t(m) * bins_ + d) * 3 + ch) * 6 + k] = c.poly[ch][(size_t(m) * bins_ + d) * 6 + k];
}

void GelShader::shade(const std::vector<float>& h, std::vector<float>& out) const {
    out.resize(size_t(H_) * W_ * 3);
    const double mag_step = 0.5 * M_PI / (bins_ - 1), dir_step = 2 * M_PI / (bins_ - 1);
    auto at = [&](int r, int c) { return double(h[size_t(r) * W_ + c]); };
    for (int r = 0; r < H_; ++r)
        for (int c = 0; c < W_; ++c) {
            // numpy.gradient: central differences inside, one-sided at the borders.
            double g_row = r == 0        ? at(1, c) - at(0, c)
                           : r == H_ - 1 ? at(r, c) - at(r - 1, c)
                                         : 0.5 * (at(r + 1, c) - at(r - 1, c));
            double g_col = c == 0        ? at(r, 1) - at(r, 0)
                           : c == W_ - 1 ? at(r, c) - at(r, c - 1)
                                         : 0.5 * (at(r, c + 1) - at(r, c - 1));
            int mag = int(std::floor(std::atan(std::sqrt(g_row * g_row + g_col * g_col)) / mag_step));
            int dir = int(std::floor((std::atan2(g_row, g_col) + M_PI) / dir_step));
            mag = std::clamp(mag, 0, bins_ - 1);
            dir = std::clamp(dir, 0, bins_ - 1);
            const double x = c, y = r;
            const double basis[6] = {x * x, y * y, x * y, x, y, 1};
            const double* p = &poly_[(size_t(mag) * bins_ + dir) * 18];
            float* o = &out[(size_t(r) * W_ + c) * 3];
            for (int ch = 0; ch < 3; ++ch) {
                double s = 0;
                for (int k = 0; k < 6; ++k) s += p[ch * 6 + k] * basis[k];
                o[ch] = float(s);
            }
        }
}

}  // namespace vtloc::sensor
