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

std::array<double, 2> height_gradient(const std::vector<float>& h, int H, int W, int r, int c) {
    auto at = [&](int y, int x) { return double(h[size_t(y) * size_t(W) + size_t(x)]); };
    // numpy.gradient: central differences inside, one-sided at the borders.
    const double g_row = H == 1 ? 0 : r == 0 ? at(1, c) - at(0, c) : r == H - 1 ? at(r, c) - at(r - 1, c) : 0.5 * (at(r + 1, c) - at(r - 1, c));
    const double g_col = W == 1 ? 0 : c == 0 ? at(r, 1) - at(r, 0) : c == W - 1 ? at(r, c) - at(r, c - 1) : 0.5 * (at(r, c + 1) - at(r, c - 1));
    return {g_row, g_col};
}

std::array<int, 2> table_bin(double g_row, double g_col, int bins) {
    const double mag_step = 0.5 * M_PI / (bins - 1), dir_step = 2 * M_PI / (bins - 1);
    const int mag = int(std::floor(std::atan(std::sqrt(g_row * g_row + g_col * g_col)) / mag_step));
    const int dir = int(std::floor((std::atan2(g_row, g_col) + M_PI) / dir_step));
    return {std::clamp(mag, 0, bins - 1), std::clamp(dir, 0, bins - 1)};
}

void GelShader::shade(const std::vector<float>& h, std::vector<float>& out) const {
    out.resize(size_t(H_) * W_ * 3);
    for (int r = 0; r < H_; ++r)
        for (int c = 0; c < W_; ++c) {
            const auto [g_row, g_col] = height_gradient(h, H_, W_, r, c);
            const auto [mag, dir] = table_bin(g_row, g_col, bins_);
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
