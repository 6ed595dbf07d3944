#include "engine/sim/metrics.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "base/error.h"

namespace vtloc::sim {

namespace {

double sqdist(const Point3& a, const Point3& b) {
    const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

std::vector<Point3> rows(const HostTensor& t, const char* what) {
    if (t.shape.size() != 2 || t.shape[1] < 3) throw Error(std::string(what) + " must be N x 3 or wider, got " + shape_str(t.shape));
    const size_t n = size_t(t.shape[0]), w = size_t(t.shape[1]);
    std::vector<Point3> out(n);
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < 3; ++k) out[i][k] = double(t.data[i * w + k]);
    return out;
}

// Min-max normalisation in place (all zeros when flat), as SPEC section 3.
std::vector<float> min_max(const std::vector<double>& v) {
    std::vector<float> out(v.size(), 0.0f);
    if (v.empty()) return out;
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    if (!(*hi > *lo)) return out;
    for (size_t i = 0; i < v.size(); ++i) out[i] = float((v[i] - *lo) / (*hi - *lo));
    return out;
}

}  // namespace

MetricObject MetricObject::make(const HostTensor& cloud, const HostTensor& candidates) {
    MetricObject o;
    o.points = rows(cloud, "the point cloud");
    o.candidates = rows(candidates, "the candidates");
    if (o.points.empty()) throw Error("the point cloud is empty");
    if (o.candidates.empty()) throw Error("the object has no candidate (no test touch)");
    for (const Point3& p : o.points)
        for (int k = 0; k < 3; ++k) o.centre[size_t(k)] += p[size_t(k)];
    for (double& c : o.centre) c /= double(o.points.size());
    o.scale = 0;
    for (const Point3& p : o.points) o.scale = std::max(o.scale, std::sqrt(sqdist(p, o.centre)));
    if (!(o.scale > 0) || !std::isfinite(o.scale)) throw Error("degenerate point cloud: all points coincide");
    o.diameter = sim::diameter(o.points);
    for (const Point3& p : o.points) o.points_n.push_back(o.normalise(p));
    for (const Point3& c : o.candidates) o.candidates_n.push_back(o.normalise(c));
    return o;
}

Point3 MetricObject::normalise(const Point3& p) const {
    return {(p[0] - centre[0]) / scale, (p[1] - centre[1]) / scale, (p[2] - centre[2]) / scale};
}

double diameter(const std::vector<Point3>& points) {
    double best = 0;
    for (size_t i = 0; i < points.size(); ++i)
        for (size_t j = i + 1; j < points.size(); ++j) best = std::max(best, sqdist(points[i], points[j]));
    return std::sqrt(best);
}

std::vector<int> order_by_distance(const std::vector<Point3>& candidates, const Point3& q) {
    std::vector<double> d(candidates.size());
    for (size_t j = 0; j < candidates.size(); ++j) d[j] = sqdist(candidates[j], q);
    std::vector<int> order(candidates.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return d[size_t(a)] < d[size_t(b)]; });
    return order;
}

int nearest(const std::vector<Point3>& candidates, const Point3& q) {
    int best = -1;
    double best_d = 0;
    for (size_t j = 0; j < candidates.size(); ++j) {
        const double d = sqdist(candidates[j], q);
        if (best < 0 || d < best_d) best = int(j), best_d = d;
    }
    return best;
}

std::vector<float> topk_heatmap(const std::vector<Point3>& points_n, const std::vector<Point3>& centres_n) {
    std::vector<double> s(points_n.size(), 0.0);
    if (centres_n.empty()) return min_max(s);
    for (size_t i = 0; i < points_n.size(); ++i) {
        const int w = nearest(centres_n, points_n[i]);  // 0-based rank: the first centre wins ties
        s[i] = std::exp(-std::sqrt(sqdist(points_n[i], centres_n[size_t(w)]))) / double(w + 1);
    }
    return min_max(s);
}

std::vector<float> gt_heatmap(const std::vector<Point3>& points_n, const Point3& gt_n) {
    std::vector<double> s(points_n.size());
    for (size_t i = 0; i < points_n.size(); ++i) s[i] = std::exp(-std::sqrt(sqdist(points_n[i], gt_n)));
    return min_max(s);
}

double mean_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    if (a.size() != b.size())
        throw Error("heat-maps of different sizes (" + std::to_string(a.size()) + " and " + std::to_string(b.size()) + ")");
    if (a.empty()) return 0;
    double sum = 0;
    for (size_t i = 0; i < a.size(); ++i) sum += std::abs(double(a[i]) - double(b[i]));
    return sum / double(a.size());
}

TouchMetrics touch_metrics(const MetricObject& o, const Point3& pred, const Point3& gt, std::vector<int> ranking,
                           const std::vector<float>& heat, int topk) {
    if (ranking.empty()) ranking = order_by_distance(o.candidates_n, o.normalise(pred));
    if (ranking.size() != o.candidates.size())
        throw Error("a ranking of " + std::to_string(ranking.size()) + " candidates for an object with " +
                    std::to_string(o.candidates.size()));
    TouchMetrics m;
    m.error_mm = std::sqrt(sqdist(pred, gt));
    m.nd = o.diameter > 0 ? 100.0 * m.error_mm / o.diameter : 0.0;
    const Point3 gt_n = o.normalise(gt);
    const int truth = nearest(o.candidates_n, gt_n);
    m.rank = int(std::find(ranking.begin(), ranking.end(), truth) - ranking.begin()) + 1;
    const std::vector<float> g = gt_heatmap(o.points_n, gt_n);
    if (!heat.empty()) {
        m.mpe = mean_abs_diff(heat, g);
    } else {
        const size_t k = std::min<size_t>(size_t(std::max(topk, 1)), ranking.size());
        std::vector<Point3> centres;
        for (size_t j = 0; j < k; ++j) centres.push_back(o.candidates_n[size_t(ranking[j])]);
        m.mpe = mean_abs_diff(topk_heatmap(o.points_n, centres), g);
    }
    return m;
}

std::vector<std::vector<float>> chance_heatmaps(const MetricObject& o, int topk) {
    std::vector<std::vector<float>> out;
    const size_t k = std::min<size_t>(size_t(std::max(topk, 1)), o.candidates.size());
    for (const Point3& c : o.candidates_n) {
        const std::vector<int> order = order_by_distance(o.candidates_n, c);
        std::vector<Point3> centres;
        for (size_t j = 0; j < k; ++j) centres.push_back(o.candidates_n[size_t(order[j])]);
        out.push_back(topk_heatmap(o.points_n, centres));
    }
    return out;
}

ChanceMetrics chance_metrics(const MetricObject& o, const Point3& gt, const std::vector<std::vector<float>>& heats,
                             int topk) {
    if (heats.size() != o.candidates.size()) throw Error("chance_metrics: one heat-map per candidate needed");
    ChanceMetrics c;
    const double n = double(o.candidates.size());
    for (size_t j = 0; j < o.candidates.size(); ++j) {
        const TouchMetrics m = touch_metrics(o, o.candidates[j], gt, {}, heats[j], topk);
        c.error_mm += m.error_mm / n;
        c.nd += m.nd / n;
        c.top1 += (m.rank == 1 ? 1.0 : 0.0) / n;
        c.top5 += (m.rank <= 5 ? 1.0 : 0.0) / n;
        c.mpe += m.mpe / n;
    }
    return c;
}

TouchScore score(const TouchMetrics& m) {
    return {m.error_mm, m.nd, m.rank == 1 ? 1.0 : 0.0, m.rank <= 5 ? 1.0 : 0.0, m.mpe};
}

TouchScore score(const ChanceMetrics& m) { return {m.error_mm, m.nd, m.top1, m.top5, m.mpe}; }

RowMetrics aggregate(const std::vector<std::vector<TouchScore>>& per_object) {
    RowMetrics r;
    for (const std::vector<TouchScore>& touches : per_object) {
        if (touches.empty()) continue;
        TouchScore mean;
        for (const TouchScore& t : touches) {
            mean.error_mm += t.error_mm;
            mean.nd += t.nd;
            mean.top1 += t.top1;
            mean.top5 += t.top5;
            mean.mpe += t.mpe;
        }
        const double n = double(touches.size());
        r.mm += mean.error_mm / n;
        r.nd += mean.nd / n;
        r.top1 += mean.top1 / n;
        r.top5 += mean.top5 / n;
        r.mpe += mean.mpe / n;
        r.objects += 1;
        r.touches += int(touches.size());
    }
    if (r.objects > 0) {
        const double n = double(r.objects);
        r.mm /= n;
        r.nd /= n;
        r.top1 *= 100.0 / n;
        r.top5 *= 100.0 / n;
        r.mpe /= n;
    }
    return r;
}

}  // namespace vtloc::sim
