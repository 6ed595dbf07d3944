// A touch: sensor frame from the contact point and normal, the object's
// height field over the window plus a 2 mm margin (height_field.h), gel
// placed at first contact and pressed, Taxim-style drape, shading and
// appearance (gel_shading.h).
#include "engine/sim/touch_renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "base/error.h"
#include "engine/sensor/gel_shading.h"
#include "engine/sim/frame_finish.h"
#include "engine/sensor/height_field.h"

namespace vtloc::sim {

namespace {

using sensor::V3;

constexpr double kMarginMm = 2.0;  // the sensor body reaches this far beyond its window

double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(const V3& a, const V3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
V3 scale(const V3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
V3 add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
bool finite(const V3& a) { return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]); }
V3 unit(const V3& a) {
    double n = std::sqrt(dot(a, a));
    return n > 0 && std::isfinite(n) ? scale(a, 1 / n) : V3{0, 0, 0};
}

// A fixed tangent basis of unit a: from the world axis least aligned with it,
// so the sensor's spin angle means the same thing for the same normal.
void tangents(const V3& a, V3& t1, V3& t2) {
    V3 e = std::abs(a[0]) <= std::abs(a[1]) && std::abs(a[0]) <= std::abs(a[2]) ? V3{1, 0, 0}
           : std::abs(a[1]) <= std::abs(a[2])                                   ? V3{0, 1, 0}
                                                                                : V3{0, 0, 1};
    t1 = unit(add(e, scale(a, -dot(e, a))));
    t2 = cross(a, t1);
}

}  // namespace

struct TouchRenderer::Impl {
    Calibration calib;
    double mm_per_px = 0;
    sensor::MeshCache mesh;
    sensor::GelShader shader;
    std::vector<float> bg_shading;  // the undeformed gel's shading (no background)

    Impl(const Calibration& c, const io::TriangleMesh& m, double mmpp)
        : calib(c), mm_per_px(mmpp), mesh(m), shader(c) {
        shader.shade(calib.depth_bg, bg_shading);
    }

    const std::vector<float>& background(const Appearance& look) const {
        if (look.background.empty()) return calib.real_bg;
        if (look.background.size() != calib.real_bg.size())
            throw Error("touch renderer: Appearance.background has " + std::to_string(look.background.size()) +
                        " values, expected " + std::to_string(calib.height) + "x" + std::to_string(calib.width) + "x3");
        return look.background;
    }

    Touch touch(const sensor::SensorFrame& f, double press, const Appearance& look, uint64_t seed, bool strict,
                const std::vector<double>& sigmas) const;
};

TouchRenderer::TouchRenderer(const Calibration& calib, const io::TriangleMesh& mesh, std::optional<double> mm_per_px)
    : drape_sigmas_mm_(sensor::default_drape_sigmas_mm()) {
    const size_t px = size_t(calib.height) * calib.width;
    if (calib.height < 3 || calib.width < 3 || calib.bins < 2 || calib.real_bg.size() != px * 3 ||
        calib.depth_bg.size() != px || calib.poly[0].size() != size_t(calib.bins) * calib.bins * 6 ||
        calib.poly[1].size() != calib.poly[0].size() || calib.poly[2].size() != calib.poly[0].size())
        throw Error("touch renderer: the calibration's tensors do not match its " + std::to_string(calib.height) + "x" +
                    std::to_string(calib.width) + " pixels and " + std::to_string(calib.bins) + " bins");
    double mmpp = mm_per_px.value_or(calib.mm_per_px);
    if (!(mmpp > 0) || !std::isfinite(mmpp)) throw Error("touch renderer: mm_per_px must be > 0");
    impl_ = std::make_shared<const Impl>(calib, mesh, mmpp);
}

const Calibration& TouchRenderer::calibration() const { return impl_->calib; }
double TouchRenderer::mm_per_px() const { return impl_->mm_per_px; }
void TouchRenderer::set_drape_sigmas_mm(std::vector<double> s) { drape_sigmas_mm_ = std::move(s); }
const std::vector<double>& TouchRenderer::drape_sigmas_mm() const { return drape_sigmas_mm_; }

std::vector<uint8_t> TouchRenderer::background_frame(const Appearance& look) const {
    const Calibration& c = impl_->calib;
    return detail::finish_frame(impl_->bg_shading, impl_->background(look), c.height, c.width, look, 0, false);
}

Touch TouchRenderer::render(const Vec3& point, const Vec3& normal, const TouchParams& p, const Appearance& look,
                            uint64_t seed) const {
    if (!(p.tilt_deg >= 0 && p.tilt_deg <= 80) || !std::isfinite(p.spin_deg) || !std::isfinite(p.tilt_dir_deg))
        throw Error("touch renderer: tilt_deg must be 0..80 and the angles finite");
    Touch bad;
    V3 n = unit(normal);
    if (!finite(point) || dot(n, n) == 0) {
        bad.reason = "point or normal is not finite or the normal is zero";
        return bad;
    }
    const double d2r = M_PI / 180;
    V3 t1, t2;
    tangents(n, t1, t2);
    const double tilt = p.tilt_deg * d2r, dir = p.tilt_dir_deg * d2r;
    V3 lean = add(scale(t1, std::cos(dir)), scale(t2, std::sin(dir)));
    sensor::SensorFrame f;
    f.z = unit(scale(add(scale(n, std::cos(tilt)), scale(lean, std::sin(tilt))), -1));
    tangents(f.z, t1, t2);
    const double spin = p.spin_deg * d2r;
    f.x = unit(add(scale(t1, std::cos(spin)), scale(t2, std::sin(spin))));
    f.y = cross(f.z, f.x);  // x cross y = z: a right-handed frame
    f.origin = point;
    return impl_->touch(f, p.press_mm, look, seed, true, drape_sigmas_mm_);
}

Touch TouchRenderer::render_at(const SensorPose& s, double press_mm, const Appearance& look, uint64_t seed) const {
    sensor::SensorFrame f;
    for (int k = 0; k < 3; ++k) f.x[k] = s.R[k * 3 + 0], f.y[k] = s.R[k * 3 + 1], f.z[k] = s.R[k * 3 + 2];
    f.origin = s.t;
    const double tol = 1e-6;
    if (!finite(f.origin) || std::abs(dot(f.x, f.x) - 1) > tol || std::abs(dot(f.y, f.y) - 1) > tol ||
        std::abs(dot(f.x, f.y)) > tol || std::abs(dot(cross(f.x, f.y), f.z) - 1) > tol)
        throw Error("touch renderer: render_at needs a finite pose with a right-handed orthonormal R");
    return impl_->touch(f, press_mm, look, seed, false, drape_sigmas_mm_);
}

Touch TouchRenderer::Impl::touch(const sensor::SensorFrame& f, double press, const Appearance& look, uint64_t seed,
                                 bool strict, const std::vector<double>& sigmas) const {
    if (!(press > 0 && press <= 20)) throw Error("touch renderer: press_mm must be in (0, 20]");
    if (!(look.noise_sigma >= 0) || !(look.blur_sigma_px >= 0) || !(look.blur_sigma_px <= 100) ||
        !std::isfinite(look.noise_sigma) || !std::isfinite(look.brightness) || !finite(look.gain))
        throw Error("touch renderer: Appearance needs finite values, noise_sigma >= 0 and blur 0..100 px");
    const std::vector<float>& bg = background(look);

    const int H = calib.height, W = calib.width;
    // The margin in pixels, capped at a window's size (a user's very fine pixel size must not explode the grid).
    const int M = int(std::min(std::ceil(kMarginMm / mm_per_px - 1e-9), double(std::max(H, W))));
    sensor::PixelGrid g{H + 2 * M, W + 2 * M, mm_per_px, 0, 0};
    sensor::HeightField hf = sensor::rasterise(mesh, f, g);

    Touch out;
    if (strict && !hf.centre_hit) {
        out.reason = "centre ray misses the mesh";
        return out;
    }
    double w0 = hf.vertex_min;
    for (double w : hf.w) w0 = std::min(w0, w);
    if (!std::isfinite(w0)) {
        out.reason = "no part of the mesh lies under the sensor";
        return out;
    }
    const double ws = w0 + press;  // the pressed gel plane's depth
    if (strict && !(ws - hf.centre_w > 0)) {
        out.reason = "gel hits other geometry first";
        return out;
    }

    // Undeformed intersection of the pressed gel plane with the object.
    std::vector<float> ind(hf.w.size());
    for (size_t i = 0; i < ind.size(); ++i) ind[i] = float(std::max(0.0, ws - hf.w[i]));
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) out.contact_pixels += ind[size_t(r + M) * g.cols + c + M] > 0;
    sensor::drape_gel(ind, g.rows, g.cols, mm_per_px, sigmas);

    out.indentation_mm.resize(size_t(H) * W);
    std::vector<float> height(size_t(H) * W);
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            size_t i = size_t(r) * W + c;
            out.indentation_mm[i] = ind[size_t(r + M) * g.cols + c + M];
            height[i] = float(calib.depth_bg[i] + out.indentation_mm[i] / mm_per_px);
        }
    std::vector<float> shading;
    shader.shade(height, shading);
    out.image = detail::finish_frame(shading, bg, H, W, look, seed, true);

    for (int k = 0; k < 3; ++k) out.pose.R[k * 3 + 0] = f.x[k], out.pose.R[k * 3 + 1] = f.y[k], out.pose.R[k * 3 + 2] = f.z[k];
    out.pose.t = add(f.origin, scale(f.z, ws));
    if (hf.centre_hit) {
        out.contact = add(f.origin, scale(f.z, hf.centre_w));
        const double* nn = &mesh.normal[size_t(hf.centre_tri) * 3];
        V3 nv{nn[0], nn[1], nn[2]};
        out.normal = dot(nv, f.z) > 0 ? scale(nv, -1) : nv;
    }
    out.ok = true;
    return out;
}

}  // namespace vtloc::sim
