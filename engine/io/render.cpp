#include "engine/io/render.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "base/error.h"
#include "engine/io/colormap.h"

namespace vtloc::io {

namespace {

using V3 = cv::Vec3d;

// Light panels: the dark (unlikely) end of the colour map stays distinct, the hot end is ringed by orange.
const cv::Scalar kBackground(242, 243, 246), kPanel(221, 223, 229), kText(28, 30, 36), kDim(105, 108, 118);
const cv::Scalar kGroundTruth(70, 230, 120);
constexpr int kSuper = 2;  // discs are drawn at 2x and averaged down: smooth edges without per-disc AA cost
constexpr int kSideWidth = 260;  // the side bar right of the two views

V3 unit(V3 v) {
    double n = cv::norm(v);
    return n > 0 ? v / n : v;
}

// Any unit vector perpendicular to u.
V3 perpendicular(V3 u) {
    V3 a = std::abs(u[0]) < 0.9 ? V3(1, 0, 0) : V3(0, 1, 0);
    return unit(a - u * a.dot(u));
}

struct Camera {
    V3 right, up, toward;  // toward = from the object to the viewer
};

// Camera looking along -toward, where toward has horizontal direction `dir`
// (perpendicular to up), turned by `turn_deg` about up, at elevation `elev_deg`.
Camera make_camera(V3 up, V3 dir, double turn_deg, double elev_deg) {
    double t = turn_deg * CV_PI / 180, e = elev_deg * CV_PI / 180;
    V3 d = dir * std::cos(t) + up.cross(dir) * std::sin(t);
    Camera c;
    c.toward = unit(d * std::cos(e) + up * std::sin(e));
    c.right = unit(up.cross(c.toward));
    c.up = c.toward.cross(c.right);
    return c;
}

void text(cv::Mat& img, const std::string& s, cv::Point org, double scale, cv::Scalar color, int thick = 1) {
    cv::putText(img, s, org, cv::FONT_HERSHEY_SIMPLEX, scale, color, thick, cv::LINE_AA);
}

// White-ringed cross for the prediction, green diamond for the truth, both
// with a dark outline so that they read on any colour.
void predicted_marker(cv::Mat& img, cv::Point p) {
    for (int pass = 0; pass < 2; ++pass) {
        cv::Scalar c = pass ? cv::Scalar(255, 255, 255) : cv::Scalar(0, 0, 0);
        int w = pass ? 2 : 5;
        cv::circle(img, p, 11, c, w, cv::LINE_AA);
        cv::line(img, p + cv::Point(-17, 0), p + cv::Point(-5, 0), c, w, cv::LINE_AA);
        cv::line(img, p + cv::Point(5, 0), p + cv::Point(17, 0), c, w, cv::LINE_AA);
        cv::line(img, p + cv::Point(0, -17), p + cv::Point(0, -5), c, w, cv::LINE_AA);
        cv::line(img, p + cv::Point(0, 5), p + cv::Point(0, 17), c, w, cv::LINE_AA);
    }
}

void truth_marker(cv::Mat& img, cv::Point p) {
    std::vector<cv::Point> d = {p + cv::Point(0, -10), p + cv::Point(10, 0), p + cv::Point(0, 10), p + cv::Point(-10, 0)};
    cv::polylines(img, d, true, cv::Scalar(0, 0, 0), 5, cv::LINE_AA);
    cv::polylines(img, d, true, kGroundTruth, 2, cv::LINE_AA);
}

struct Scene {
    const HostTensor& cloud;
    std::span<const float> heat;
    V3 centre;
    double radius = 1, spacing = 1;
};

// Darkens pixels on the near side of a depth jump larger than `jump` (object units) between drawn
// pixels: outlines a handle in front of a body or a rim in front of an inner wall, which
// share colours and would otherwise merge. Gaps between discs are not outlined.
void outline_depth_jumps(cv::Mat& img, const cv::Mat& depth, double jump) {
    constexpr float kEmpty = -1e29f;
    constexpr int kReach = 2;  // pixels at 2x: about one final pixel wide
    cv::Mat mark(depth.size(), CV_8U, cv::Scalar(0));
    for (int y = kReach; y < depth.rows - kReach; ++y)
        for (int x = kReach; x < depth.cols - kReach; ++x) {
            float d = depth.at<float>(y, x);
            if (d < kEmpty) continue;
            for (auto [dx, dy] : {std::pair{kReach, 0}, {-kReach, 0}, {0, kReach}, {0, -kReach}}) {
                float e = depth.at<float>(y + dy, x + dx);
                if (e > kEmpty && e < d - jump) mark.at<uint8_t>(y, x) = 1;
            }
        }
    for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x)
            if (mark.at<uint8_t>(y, x)) img.at<cv::Vec3b>(y, x) = img.at<cv::Vec3b>(y, x) * 0.3;
}

// The view's screen-plane bounding box (object units, x right, y up) of the points and markers.
cv::Rect2d view_box(const Scene& s, const Camera& cam, const RenderOptions& o) {
    double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
    auto add = [&](V3 p) {
        V3 q = p - s.centre;
        x0 = std::min(x0, q.dot(cam.right)), x1 = std::max(x1, q.dot(cam.right));
        y0 = std::min(y0, q.dot(cam.up)), y1 = std::max(y1, q.dot(cam.up));
    };
    for (int64_t i = 0; i < s.cloud.shape[0]; ++i)
        add(V3(s.cloud.data[size_t(i) * 6], s.cloud.data[size_t(i) * 6 + 1], s.cloud.data[size_t(i) * 6 + 2]));
    for (auto& m : {o.contact, o.ground_truth})
        if (m) add(V3((*m)[0], (*m)[1], (*m)[2]));
    return {x0, y0, std::max(x1 - x0, 1e-9), std::max(y1 - y0, 1e-9)};
}

// A view's projection onto its supersampled canvas (W x H pixels at kSuper x).
struct Projection {
    const Scene& s;
    const Camera& cam;
    cv::Point2d mid;
    double scale;
    int W, H;
    cv::Point2d operator()(V3 p, double& z) const {
        V3 q = p - s.centre;
        z = q.dot(cam.toward);
        return cv::Point2d(W / 2.0 + (q.dot(cam.right) - mid.x) * scale, H / 2.0 - (q.dot(cam.up) - mid.y) * scale);
    }
};

// The cloud's discs, far to near, into `big`; `depth` gets the nearest front-facing depth per
// pixel. Returns the disc radius (supersampled pixels).
double draw_points(cv::Mat& big, cv::Mat& depth, const Projection& project) {
    const Scene& s = project.s;
    const Camera& cam = project.cam;
    const int n = int(s.cloud.shape[0]);
    const int W = project.W, H = project.H;
    const double scale = project.scale;
    std::vector<double> z(static_cast<size_t>(n));
    std::vector<cv::Point2d> xy(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        const float* p = &s.cloud.data[size_t(i) * 6];
        xy[size_t(i)] = project(V3(p[0], p[1], p[2]), z[size_t(i)]);
    }
    std::vector<int> order(static_cast<size_t>(n));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return z[size_t(a)] < z[size_t(b)]; });
    const double r = std::clamp(0.75 * s.spacing * scale, 1.5 * kSuper, 0.03 * std::min(W, H));
    const V3 light = unit(cam.right * -0.45 + cam.up * 0.6 + cam.toward * 0.75);
    const double z_near = z.empty() ? 0 : z[size_t(order.back())], z_far = z.empty() ? 0 : z[size_t(order.front())];
    constexpr int kShift = 4;  // sub-pixel disc centres
    for (int i : order) {
        const float* p = &s.cloud.data[size_t(i) * 6];
        V3 nrm(p[3], p[4], p[5]);
        bool front = nrm.dot(cam.toward) >= 0;
        double lambert = std::max(0.0, (front ? nrm : -nrm).dot(light));
        double shade = 0.5 + 0.5 * lambert;
        auto c = heat_color(s.heat[size_t(i)]);
        cv::Scalar fill(c[0] * shade, c[1] * shade, c[2] * shade);
        // Depth cues: points of a surface turned away (the far side of a closed surface, hidden
        // when the surface is dense) are small faint dots; the rest fade a little with distance.
        double fade = (front ? 0.0 : 0.75) + 0.25 * (z_near - z[size_t(i)]) / std::max(z_near - z_far, 1e-12);
        fill = fill * (1 - fade) + kPanel * fade;
        cv::Point ctr(int(std::lround(xy[size_t(i)].x * (1 << kShift))), int(std::lround(xy[size_t(i)].y * (1 << kShift))));
        int rr = int(std::lround((front ? r : 0.35 * r) * (1 << kShift)));
        cv::circle(big, ctr, rr, fill * 0.7, cv::FILLED, cv::LINE_8, kShift);  // darker rim
        cv::circle(big, ctr, int(rr * 0.84), fill, cv::FILLED, cv::LINE_8, kShift);
        if (front) cv::circle(depth, ctr, rr, cv::Scalar(z[size_t(i)]), cv::FILLED, cv::LINE_8, kShift);
    }
    return r;
}

// The contact and truth markers on the final-size panel; `depth` and `r` from draw_points.
void draw_markers(cv::Mat& panel, const cv::Mat& depth, double r, const Projection& project, const RenderOptions& o) {
    const Scene& s = project.s;
    const int W = project.W, H = project.H;
    // Markers, faded when a surface in front of them is nearer by more than 1.5 point spacings
    // plus 2% of the object's size (the nearest depth in a small window around the marker, so
    // that a gap between discs does not count as a view through).
    auto place = [&](const std::array<float, 3>& m, bool& visible) {
        double mz;
        cv::Point2d q = project(V3(m[0], m[1], m[2]), mz);
        int qx = int(std::lround(q.x)), qy = int(std::lround(q.y)), w = int(std::ceil(0.5 * r));
        cv::Rect win = cv::Rect(qx - w, qy - w, 2 * w + 1, 2 * w + 1) & cv::Rect(0, 0, W, H);
        double nearest = -1e30;
        if (win.area() > 0) cv::minMaxLoc(depth(win), nullptr, &nearest);
        visible = mz >= nearest - 1.5 * s.spacing - 0.02 * s.radius;
        return cv::Point(int(std::lround(q.x / kSuper)), int(std::lround(q.y / kSuper)));
    };
    bool pv = true, gv = true;
    cv::Point pp, gp;
    if (o.contact) pp = place(*o.contact, pv);
    if (o.ground_truth) gp = place(*o.ground_truth, gv);
    auto draw_markers = [&](cv::Mat& img, bool visible_pass) {
        if (o.contact && o.ground_truth && visible_pass == (pv && gv))
            cv::line(img, pp, gp, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
        if (o.ground_truth && gv == visible_pass) truth_marker(img, gp);
        if (o.contact && pv == visible_pass) predicted_marker(img, pp);
    };
    if ((o.contact && !pv) || (o.ground_truth && !gv)) {  // hidden markers: 40% opaque
        cv::Mat overlay = panel.clone();
        draw_markers(overlay, false);
        cv::addWeighted(overlay, 0.4, panel, 0.6, 0, panel);
    }
    draw_markers(panel, true);
}

// Axis triad (object axes as this view shows them) and the view's label.
void axes_and_label(cv::Mat& panel, const Camera& cam, const std::string& label) {
    cv::Point origin(34, panel.rows - 34);
    const char* names[3] = {"x", "y", "z"};
    const cv::Scalar axis_col[3] = {cv::Scalar(235, 90, 80), cv::Scalar(90, 210, 100), cv::Scalar(100, 150, 255)};
    for (int a = 0; a < 3; ++a) {
        V3 e(a == 0, a == 1, a == 2);
        cv::Point tip = origin + cv::Point(int(std::lround(e.dot(cam.right) * 22)), int(std::lround(-e.dot(cam.up) * 22)));
        cv::line(panel, origin, tip, axis_col[a], 2, cv::LINE_AA);
        text(panel, names[a], tip + cv::Point(3, 4), 0.45, axis_col[a]);
    }
    text(panel, label, cv::Point(12, 24), 0.55, kText);
}

// One view, drawn in place into `panel` (a region of the final image).
void draw_view(cv::Mat panel, const Scene& s, const Camera& cam, double px_per_unit, cv::Point2d mid,
               const RenderOptions& o, const std::string& label) {
    const int W = panel.cols * kSuper, H = panel.rows * kSuper;
    cv::Mat big(H, W, CV_8UC3, kPanel);
    cv::Mat depth(H, W, CV_32F, cv::Scalar(-1e30));  // nearest depth drawn per pixel (painter's order)
    const Projection project{s, cam, mid, px_per_unit * kSuper, W, H};
    const double r = draw_points(big, depth, project);
    outline_depth_jumps(big, depth, 2.5 * s.spacing);
    cv::resize(big, panel, panel.size(), 0, 0, cv::INTER_AREA);
    draw_markers(panel, depth, r, project, o);
    axes_and_label(panel, cam, label);
}

// Vertical colour bar with its ticks, top-left corner at `at`.
void colour_bar(cv::Mat& img, cv::Point at, int h) {
    text(img, "contact probability", at + cv::Point(0, -12), 0.5, kText);
    for (int y = 0; y < h; ++y) {
        auto c = heat_color(1.0f - float(y) / float(h - 1));
        cv::line(img, at + cv::Point(0, y), at + cv::Point(22, y), cv::Scalar(c[0], c[1], c[2]));
    }
    cv::rectangle(img, at - cv::Point(1, 1), at + cv::Point(23, h), kDim, 1);
    const char* ticks[3] = {"1.0  likely", "0.5", "0.0  unlikely"};
    for (int k = 0; k < 3; ++k) {
        int y = at.y + (h - 1) * k / 2;
        cv::line(img, cv::Point(at.x + 23, y), cv::Point(at.x + 28, y), kDim);
        text(img, ticks[k], cv::Point(at.x + 33, y + 5), 0.45, kText);
    }
}

// The cloud's centre, radius and point spacing.
Scene make_scene(const HostTensor& cloud, std::span<const float> heat) {
    const int n = int(cloud.shape[0]);
    Scene s{cloud, heat, V3(0, 0, 0)};
    for (int i = 0; i < n; ++i) s.centre += V3(cloud.data[size_t(i) * 6], cloud.data[size_t(i) * 6 + 1], cloud.data[size_t(i) * 6 + 2]);
    s.centre /= n;
    auto pt = [&](int i) { return V3(cloud.data[size_t(i) * 6], cloud.data[size_t(i) * 6 + 1], cloud.data[size_t(i) * 6 + 2]); };
    s.radius = 1e-9;
    for (int i = 0; i < n; ++i) s.radius = std::max(s.radius, cv::norm(pt(i) - s.centre));
    // Point spacing, for the disc size: twice the mean nearest-neighbour distance (over up to 256
    // points), since for random samples that mean is about half of sqrt(area / N).
    int stride = std::max(1, n / 256), probes = 0;
    double sum = 0;
    for (int i = 0; i < n; i += stride, ++probes) {
        double best = 1e300;
        for (int j = 0; j < n; ++j)
            if (j != i) best = std::min(best, cv::norm(pt(i) - pt(j)));
        sum += n > 1 ? best : s.radius * 0.05;
    }
    s.spacing = std::max(2 * sum / probes, s.radius * 1e-3);
    return s;
}

// The two views: a 3/4 view of the widest side (or facing the contact) and the opposite side.
std::pair<Camera, Camera> choose_cameras(const Scene& s, const RenderOptions& o) {
    const HostTensor& cloud = s.cloud;
    const int n = int(cloud.shape[0]);
    auto pt = [&](int i) { return V3(cloud.data[size_t(i) * 6], cloud.data[size_t(i) * 6 + 1], cloud.data[size_t(i) * 6 + 2]); };
    // Horizontal frame around the up axis.
    V3 up = unit(V3(o.up[0], o.up[1], o.up[2]));
    if (cv::norm(up) == 0) up = V3(0, 1, 0);
    V3 h1 = perpendicular(up), h2 = up.cross(h1);
    // Default direction: the horizontal axis of least spread, so the widest side faces the viewer.
    double sxx = 0, sxy = 0, syy = 0;
    for (int i = 0; i < n; ++i) {
        V3 q = pt(i) - s.centre;
        double a = q.dot(h1), b = q.dot(h2);
        sxx += a * a, sxy += a * b, syy += b * b;
    }
    double theta = 0.5 * std::atan2(2 * sxy, sxx - syy) + CV_PI / 2;  // minor axis angle
    V3 dir = unit(h1 * std::cos(theta) + h2 * std::sin(theta));
    double turn = 35, elev = 25;
    if (o.contact) {
        // Show the contact: take the 3/4 view (of the four around the widest side) that faces it
        // best when it is within 60 degrees of the contact's direction (the surface normal at the
        // nearest point, else the offset from the centre), else look along that direction.
        V3 c((*o.contact)[0], (*o.contact)[1], (*o.contact)[2]);
        int best = 0;
        for (int i = 1; i < n; ++i)
            if (cv::norm(pt(i) - c) < cv::norm(pt(best) - c)) best = i;
        V3 nrm(cloud.data[size_t(best) * 6 + 3], cloud.data[size_t(best) * 6 + 4], cloud.data[size_t(best) * 6 + 5]);
        V3 horiz = nrm - up * nrm.dot(up), off = (c - s.centre) - up * (c - s.centre).dot(up);
        V3 want = cv::norm(horiz) > 0.2 ? unit(horiz) : cv::norm(off) > 1e-6 * s.radius ? unit(off) : dir;
        double best_cos = -2;
        V3 best_dir = dir;
        for (V3 d : {dir, -dir})
            for (double t : {35.0, -35.0}) {
                double a = t * CV_PI / 180, cs = (d * std::cos(a) + up.cross(d) * std::sin(a)).dot(want);
                if (cs > best_cos) best_cos = cs, best_dir = d, turn = t;
            }
        if (best_cos >= 0.5) dir = best_dir;
        else dir = want, turn = 20;
        elev = std::clamp(std::asin(std::clamp(nrm.dot(up), -1.0, 1.0)) * 180 / CV_PI + 20, -60.0, 65.0);
    }
    return {make_camera(up, dir, turn, elev), make_camera(up, -dir, turn, 20)};
}

// The side bar below its top `y`: tactile inset, marker legend, colour bar.
void side_bar(cv::Mat& img, const RenderOptions& o, int sx, int y) {
    if (o.tactile && o.tactile->width > 0 && o.tactile->height > 0) {
        text(img, "tactile image", cv::Point(sx, y), 0.5, kText);
        cv::Mat t(o.tactile->height, o.tactile->width, CV_8UC3, const_cast<uint8_t*>(o.tactile->pixels.data()));
        int tw = kSideWidth - 30, th = std::min(int(std::lround(double(tw) * t.rows / t.cols)), 200);
        tw = std::min(tw, int(std::lround(double(th) * t.cols / t.rows)));
        cv::Mat dst = img(cv::Rect(sx, y + 8, tw, th));
        cv::resize(t, dst, dst.size(), 0, 0, tw < t.cols ? cv::INTER_AREA : cv::INTER_LINEAR);
        y += th + 40;
    }
    if (o.contact) {
        predicted_marker(img, cv::Point(sx + 16, y));
        text(img, "predicted contact", cv::Point(sx + 42, y + 5), 0.5, kText);
        y += 36;
    }
    if (o.ground_truth) {
        truth_marker(img, cv::Point(sx + 16, y));
        text(img, "true contact", cv::Point(sx + 42, y + 5), 0.5, kText);
        y += 36;
    }
    if (o.contact || o.ground_truth) {
        text(img, "faded: behind the surface", cv::Point(sx, y), 0.42, kDim);
        y += 34;
    }
    int bar_h = std::min(220, o.height - y - 40);
    if (bar_h > 60) colour_bar(img, cv::Point(sx + 4, y + 14), bar_h);
}

}  // namespace

RgbImage render_heatmap(const HostTensor& cloud, std::span<const float> heat, const RenderOptions& o) {
    if (cloud.shape.size() != 2 || cloud.shape[1] != 6 || cloud.shape[0] < 1)
        throw Error("render_heatmap: cloud must be N x 6 with N >= 1, got " + shape_str(cloud.shape));
    if (size_t(cloud.shape[0]) != heat.size())
        throw Error("render_heatmap: " + std::to_string(heat.size()) + " heat values for " +
                    std::to_string(cloud.shape[0]) + " points");
    if (o.width < 640 || o.height < 400) throw Error("render_heatmap: image must be at least 640 x 400");
    const Scene s = make_scene(cloud, heat);
    const auto [front, back] = choose_cameras(s, o);

    // Layout: caption bar, two views, side bar (tactile inset, legend, colour bar).
    cv::Mat img(o.height, o.width, CV_8UC3, kBackground);
    const int top = 44, side = kSideWidth, gap = 8;
    const int pw = (o.width - side - 3 * gap) / 2, ph = o.height - top - gap;
    // One scale for both views (the larger of the two fits), each centred on its own extent.
    cv::Rect2d bf = view_box(s, front, o), bb = view_box(s, back, o);
    double fit = std::min({0.86 * pw / bf.width, 0.84 * ph / bf.height, 0.86 * pw / bb.width, 0.84 * ph / bb.height});
    auto mid = [](const cv::Rect2d& b) { return cv::Point2d(b.x + b.width / 2, b.y + b.height / 2); };
    draw_view(img(cv::Rect(gap, top, pw, ph)), s, front, fit, mid(bf), o,
              o.contact ? "facing the prediction" : "3/4 view");
    draw_view(img(cv::Rect(2 * gap + pw, top, pw, ph)), s, back, fit, mid(bb), o, "opposite side");

    std::string caption = o.caption.empty() ? "VTLoc contact heat-map" : o.caption;
    double cs = 0.62;
    int base = 0;
    while (cs > 0.35 && cv::getTextSize(caption, cv::FONT_HERSHEY_SIMPLEX, cs, 1, &base).width > o.width - 24) cs -= 0.02;
    text(img, caption, cv::Point(12, 29), cs, kText);

    side_bar(img, o, o.width - side + 6, top + 22);

    RgbImage out(o.height, o.width);
    for (int r = 0; r < o.height; ++r) std::memcpy(out.at(r, 0), img.ptr<uint8_t>(r), size_t(o.width) * 3);
    return out;
}

}  // namespace vtloc::io
