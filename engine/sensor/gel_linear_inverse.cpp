#include "engine/sensor/gel_linear_inverse.h"

#include <cmath>
#include <vector>

#include "base/error.h"
#include "engine/parallel.h"
#include "engine/sensor/gel_shading.h"

namespace vtloc::sensor {

std::vector<float> build_linear_inverse(const Calibration& c, double max_slope, int threads) {
    if (!(max_slope > 0 && max_slope < 10)) throw Error("linear inverse: max_slope must be in (0, 10)");
    const int H = c.height, W = c.width, B = c.bins;
    auto colour = [&](double gr, double gc, int r, int col, double out[3]) {
        const auto [m, d] = table_bin(gr, gc, B);
        const double x = col, y = r, basis[6] = {x * x, y * y, x * y, x, y, 1};
        for (int ch = 0; ch < 3; ++ch) {
            const float* p = &c.poly[ch][(size_t(m) * size_t(B) + size_t(d)) * 6];
            double s = 0;
            for (int k = 0; k < 6; ++k) s += double(p[k]) * basis[k];
            out[ch] = s;
        }
    };
    // The rings' slopes, the same at every pixel: computed once, not 216 sines and cosines a pixel.
    std::vector<double> ring_gr, ring_gc;
    for (int ring = 1; ring <= 6; ++ring)
        for (int a = 0; a < 36; ++a) {
            const double mag = max_slope * ring / 6.0, ph = a * M_PI / 18 + 0.01;  // off the bins' edges
            ring_gr.push_back(mag * std::sin(ph)), ring_gc.push_back(mag * std::cos(ph));
        }
    std::vector<float> L(size_t(H) * size_t(W) * 6);
    parallel_for(size_t(H), threads, [&](size_t row) {  // rows on the host's threads, each writing its own
        const int r = int(row);
        for (int col = 0; col < W; ++col) {
            const auto [br, bc] = height_gradient(c.depth_bg, H, W, r, col);
            double c0[3];
            colour(br, bc, r, col, c0);
            // J from dc = J g over the rings: G = sum g g^T, Y[ch] = sum g dc_ch.
            double G[3] = {0, 0, 0}, Y[3][2] = {};
            for (size_t q = 0; q < ring_gr.size(); ++q) {
                const double gr = ring_gr[q], gc = ring_gc[q];
                double c1[3];
                colour(br + gr, bc + gc, r, col, c1);
                G[0] += gr * gr, G[1] += gr * gc, G[2] += gc * gc;
                for (int ch = 0; ch < 3; ++ch) Y[ch][0] += gr * (c1[ch] - c0[ch]), Y[ch][1] += gc * (c1[ch] - c0[ch]);
            }
            const double det = G[0] * G[2] - G[1] * G[1];
            double J[3][2];
            for (int ch = 0; ch < 3; ++ch)
                J[ch][0] = (G[2] * Y[ch][0] - G[1] * Y[ch][1]) / det, J[ch][1] = (-G[1] * Y[ch][0] + G[0] * Y[ch][1]) / det;
            // L = (J^T J)^-1 J^T; a pixel whose colours do not move with the slope gets none.
            double A[3] = {0, 0, 0};
            for (int ch = 0; ch < 3; ++ch) A[0] += J[ch][0] * J[ch][0], A[1] += J[ch][0] * J[ch][1], A[2] += J[ch][1] * J[ch][1];
            const double dA = A[0] * A[2] - A[1] * A[1];
            float* out = &L[(size_t(r) * size_t(W) + size_t(col)) * 6];
            if (!(std::abs(dA) > 1e-9 * (A[0] * A[2] + 1e-30)) || !std::isfinite(dA)) continue;
            for (int ch = 0; ch < 3; ++ch) {
                out[ch] = float((A[2] * J[ch][0] - A[1] * J[ch][1]) / dA);
                out[3 + ch] = float((-A[1] * J[ch][0] + A[0] * J[ch][1]) / dA);
            }
        }
    });
    return L;
}

}  // namespace vtloc::sensor
