// The sensor rescale before the crop (rescale_tactile_image in <vtloc/vtloc.h>):
// a frame taken with pixels of one size resampled to the model's pixel size.
// Op for op the PyTorch reference's weights_tools.tactile.rescale (same
// double expressions in the same order, taps summed in the same order, no
// fused multiply-add: the project builds for baseline x86-64/ARM without
// -ffast-math), so both give the same bytes.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "engine/api/api_internal.h"
#include "engine/model/model_config.h"

namespace vtloc::api {

namespace {

constexpr int64_t kMaxRescaledSide = 16384;

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

struct Tap {
    int index;
    double weight;
};

// Output side: round(n * image_mm / model_mm), halves up, at least 1.
int64_t rescaled_side(int64_t n, double image_mm, double model_mm) {
    const double v = std::floor(double(n) * image_mm / model_mm + 0.5);
    if (!(v <= double(kMaxRescaledSide))) return kMaxRescaledSide + 1;
    return std::max<int64_t>(1, int64_t(v));
}

// Source pixels and weights of each output pixel along one axis; f = source
// pixels per output pixel. See weights_tools/tactile.py (_axis_taps).
std::vector<std::vector<Tap>> axis_taps(int64_t n_in, int64_t n_out, double f) {
    std::vector<std::vector<Tap>> taps(static_cast<size_t>(n_out));
    const double half_in = double(n_in) / 2, half_out = double(n_out) / 2;
    for (int64_t o = 0; o < n_out; ++o) {
        std::vector<Tap>& row = taps[size_t(o)];
        if (f > 1) {  // area average
            const double lo = half_in + (double(o) - half_out) * f;
            const double hi = half_in + (double(o + 1) - half_out) * f;
            const double a = std::max(lo, 0.0), b = std::min(hi, double(n_in));
            if (!(b > a)) {
                row.push_back({int(std::clamp<int64_t>(int64_t(std::floor(lo)), 0, n_in - 1)), 1.0});
                continue;
            }
            const double span = b - a;
            for (int64_t i = int64_t(std::floor(a)); i < int64_t(std::ceil(b)); ++i) {
                const double w = std::min(double(i) + 1.0, b) - std::max(double(i), a);
                if (w > 0) row.push_back({int(i), w / span});
            }
        } else {  // bilinear between pixel centres
            double src = half_in + (double(o) + 0.5 - half_out) * f - 0.5;
            src = std::min(std::max(src, 0.0), double(n_in) - 1.0);
            const int64_t i0 = int64_t(std::floor(src));
            const int64_t i1 = std::min(i0 + 1, n_in - 1);
            const double w1 = src - double(i0);
            row.push_back({int(i0), 1.0 - w1});
            row.push_back({int(i1), w1});
        }
    }
    return taps;
}

}  // namespace

void check_mm_per_px(double v, const std::string& what) {
    if (!std::isfinite(v) || !(v > 0)) throw Error(what + " must be a finite number > 0, got " + num(v));
}

TactileImage rescale_frame(const TactileImage& image, double image_mm, double model_mm) {
    check_mm_per_px(image_mm, "mm_per_px");
    check_mm_per_px(model_mm, "the model's sensor mm_per_px");
    const int64_t h = image.height, w = image.width;
    if (h < 1 || w < 1 || image.rgb.size() != size_t(h) * size_t(w) * 3)
        throw Error("the tactile image holds " + std::to_string(image.rgb.size()) + " bytes; " +
                    std::to_string(w) + "x" + std::to_string(h) + " RGB needs " +
                    std::to_string(std::max<int64_t>(h, 0) * std::max<int64_t>(w, 0) * 3));
    if (image_mm == model_mm) return image;
    const double f = model_mm / image_mm;
    const int64_t oh = rescaled_side(h, image_mm, model_mm), ow = rescaled_side(w, image_mm, model_mm);
    const std::string what = "rescaling the " + std::to_string(w) + "x" + std::to_string(h) + " frame from " +
                             num(image_mm) + " to " + num(model_mm) + " mm per pixel gives ";
    if (oh > kMaxRescaledSide || ow > kMaxRescaledSide)
        throw Error(what + "a frame over " + std::to_string(kMaxRescaledSide) + " pixels a side");
    if (oh < limits::kMinImageSide || ow < limits::kMinImageSide)
        throw Error(what + std::to_string(ow) + "x" + std::to_string(oh) + "; the smallest accepted is " +
                    std::to_string(limits::kMinImageSide) + "x" + std::to_string(limits::kMinImageSide));

    // Along each row (x) first, then along each column (y), as the reference.
    const auto tx = axis_taps(w, ow, f), ty = axis_taps(h, oh, f);
    std::vector<double> rows(size_t(h) * size_t(ow) * 3);
    for (int64_t y = 0; y < h; ++y)
        for (int64_t x = 0; x < ow; ++x)
            for (int64_t c = 0; c < 3; ++c) {
                double acc = 0.0;
                for (const Tap& t : tx[size_t(x)]) {
                    const double p = double(image.rgb[size_t((y * w + t.index) * 3 + c)]);
                    const double term = t.weight * p;
                    acc = acc + term;
                }
                rows[size_t((y * ow + x) * 3 + c)] = acc;
            }
    TactileImage out;
    out.height = int(oh);
    out.width = int(ow);
    out.rgb.resize(size_t(oh) * size_t(ow) * 3);
    for (int64_t y = 0; y < oh; ++y)
        for (int64_t x = 0; x < ow; ++x)
            for (int64_t c = 0; c < 3; ++c) {
                double acc = 0.0;
                for (const Tap& t : ty[size_t(y)]) {
                    const double term = t.weight * rows[size_t((t.index * ow + x) * 3 + c)];
                    acc = acc + term;
                }
                out.rgb[size_t((y * ow + x) * 3 + c)] = uint8_t(std::clamp(std::floor(acc + 0.5), 0.0, 255.0));
            }
    return out;
}

TactileImage rescale_tactile_image(const TactileImage& image, double image_mm_per_px, double model_mm_per_px) {
    return guarded([&] { return rescale_frame(image, image_mm_per_px, model_mm_per_px); });
}

}  // namespace vtloc::api
