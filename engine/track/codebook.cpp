#include "engine/track/codebook.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <tuple>

#include "base/error.h"
#include "engine/executor.h"
#include "engine/ops/build.h"
#include "engine/ops/codebook_bins.h"
#include "engine/ops/codebook_math.h"
#include "engine/resident_weights.h"
#include "engine/safetensors.h"
#include "engine/weights.h"

namespace vtloc::track {

namespace {

int64_t grid_cells(const CodebookOptions& o) { return 2 * int64_t(std::ceil(o.reach_mm / o.cell_mm)) + 1; }

void check_options(const CodebookOptions& o) {
    if (!(o.cell_mm >= 0.1 && o.cell_mm <= 10) || !(o.splat_mm > 0 && o.splat_mm <= 8 * o.cell_mm) || !(o.cap_mm > 0) ||
        !(o.reach_mm > 0 && o.reach_mm <= 200) || !std::isfinite(o.facing) || !(o.min_density >= 0))
        throw Error("codebook options: cell 0.1-10 mm, splat in (0, 8 cells], cap > 0, reach in (0, 200] mm");
}

std::string num(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return b;
}

std::map<std::string, std::string> metadata_of(const CodebookOptions& o, int64_t G) {
    return {{"format", Codebook::kFormat}, {"cell_mm", num(o.cell_mm)}, {"splat_mm", num(o.splat_mm)},
            {"cap_mm", num(o.cap_mm)},     {"facing", num(o.facing)},   {"reach_mm", num(o.reach_mm)},
            {"G", std::to_string(G)}};
}

}  // namespace

namespace {
// Points per mm^2 of a cloud, from the mean distance to the nearest neighbour
// (0.5 / sqrt(density) for points spread evenly over a surface), over at most
// 2000 points; a neighbour beyond the bins searched counts at the bin size.
double cloud_density(const Surface& s) {
    const BinnedPoints b = bin_points(s.dense, 0.5);
    const int64_t D = s.n_dense(), step = std::max<int64_t>(1, D / 2000);
    double sum = 0;
    int64_t n = 0;
    for (int64_t i = 0; i < D; i += step, ++n) {
        const float* p = &s.dense[size_t(6 * i)];
        int64_t c[3];
        b.cell_of(p, c);
        double best = b.coarse * b.coarse;
        for (int64_t z = std::max<int64_t>(0, c[2] - 1); z <= std::min(b.dims[2] - 1, c[2] + 1); ++z)
            for (int64_t y = std::max<int64_t>(0, c[1] - 1); y <= std::min(b.dims[1] - 1, c[1] + 1); ++y)
                for (int64_t x = std::max<int64_t>(0, c[0] - 1); x <= std::min(b.dims[0] - 1, c[0] + 1); ++x) {
                    const int64_t at[3] = {x, y, z}, bin = b.index_of(at);
                    for (int32_t k = b.bins[size_t(2 * bin)]; k < b.bins[size_t(2 * bin)] + b.bins[size_t(2 * bin + 1)]; ++k) {
                        const float* q = &b.points[size_t(6 * k)];
                        const double d = double(q[0] - p[0]) * (q[0] - p[0]) + double(q[1] - p[1]) * (q[1] - p[1]) + double(q[2] - p[2]) * (q[2] - p[2]);
                        if (d > 0 && d < best) best = d;
                    }
                }
        sum += std::sqrt(best);
    }
    const double mean = sum / double(n);
    return 0.25 / (mean * mean);
}
}  // namespace

void check_render_density(const Surface& s, const CodebookOptions& o) {
    if (s.from_mesh) return;
    const double density = cloud_density(s);
    if (density < o.min_density)
        throw Error("render-and-compare needs a dense cloud (about " + num(o.min_density) + " point per mm^2 or more); this one has about " +
                    num(density) + " per mm^2 (" + std::to_string(s.n_dense()) + " points)");
}

namespace {
// The maps [S, G*G] of `samples` ([S, 9] rows of the surface's) from its dense points.
std::vector<float> render_maps(rt::Context* ctx, const Surface& s, const std::vector<float>& samples, const CodebookOptions& o) {
    check_options(o);
    check_render_density(s, o);
    const int64_t G = grid_cells(o);
    // A bin reaches every point that can land in a map: the map's half width and the cap.
    const double half = double(G - 1) / 2 * o.cell_mm + o.splat_mm;
    const BinnedPoints bp = bin_points(s.dense, std::sqrt(2 * half * half + o.cap_mm * o.cap_mm));
    ops::CodebookRender p;
    p.G = G, p.cell = o.cell_mm, p.splat = o.splat_mm, p.cap = o.cap_mm, p.facing = o.facing, p.coarse = bp.coarse;
    p.max_bin = bp.max_bin;
    for (int k = 0; k < 3; ++k) p.origin[k] = bp.origin[k], p.dims[k] = bp.dims[k];
    Graph g;
    const int64_t S = int64_t(samples.size() / 9), D = int64_t(bp.points.size() / 6);
    g.output(ops::codebook_render(g, g.input("samples", {S, 9}), g.input("points", {D, 6}),
                                  g.input("bins", {bp.dims[0] * bp.dims[1] * bp.dims[2], 2}, ElemType::I32), p, "codebook.render"),
             "heights");
    const TensorMap in{{"samples", HostTensor({S, 9}, samples)},
                       {"points", HostTensor({D, 6}, bp.points)},
                       {"bins", HostTensor::from_ints({bp.dims[0] * bp.dims[1] * bp.dims[2], 2}, bp.bins)}};
    TensorMap out;
    if (ctx) {
        GpuExecutor ex(*ctx, g, WeightStore{});
        out = ex.run(in);
    } else {
        out = run_cpu(g, WeightStore{}, in);
    }
    return std::move(out.at("heights").data);
}
}  // namespace

Codebook render_codebook(rt::Context* ctx, const Surface& s, const CodebookOptions& o) {
    Codebook b;
    b.options = o;
    b.heights = render_maps(ctx, s, s.samples, o);  // checks the options first
    b.G = grid_cells(o);
    b.samples = s.samples;
    return b;
}

std::vector<float> render_codebook_rows(rt::Context* ctx, const Surface& s, const std::vector<int64_t>& rows, const CodebookOptions& o) {
    std::vector<float> samples;
    samples.reserve(9 * rows.size());
    for (int64_t r : rows) {
        if (r < 0 || r >= s.n_samples())
            throw Error("render_codebook_rows: sample " + std::to_string(r) + " of " + std::to_string(s.n_samples()));
        samples.insert(samples.end(), s.samples.begin() + 9 * r, s.samples.begin() + 9 * (r + 1));
    }
    if (rows.empty()) return {};
    return render_maps(ctx, s, samples, o);
}

void save_codebook(const std::string& path, const Codebook& b) {
    write_safetensors(path,
                      {TensorBlob::f32("heights", {b.n_samples(), b.G * b.G}, b.heights),
                       TensorBlob::f32("samples", {b.n_samples(), 9}, b.samples)},
                      metadata_of(b.options, b.G));
}

Codebook load_codebook(const std::string& path, const Surface& s, const CodebookOptions& o) {
    return parse_codebook(SafetensorsFile::load(path, "codebook cache"), path, s, o);
}

Codebook parse_codebook(const SafetensorsFile& f, const std::string& path, const Surface& s, const CodebookOptions& o) {
    check_options(o);
    const auto& md = f.metadata();
    const auto fmt = md.find("format");
    if (fmt == md.end() || fmt->second != Codebook::kFormat)
        throw Error(path + ": not a " + std::string(Codebook::kFormat) + " codebook (format '" +
                    (fmt == md.end() ? std::string("none") : fmt->second) + "')");
    Codebook b;
    b.options = o;
    b.G = grid_cells(o);
    if (metadata_of(o, b.G) != md)
        throw Error(path + ": a codebook rendered with other options (cell, splat, cap, facing, reach); delete it to rebuild");
    const TensorInfo& h = f.at("heights");
    const TensorInfo& sm = f.at("samples");
    if (sm.shape != Shape{s.n_samples(), 9} || h.shape != Shape{s.n_samples(), b.G * b.G})
        throw Error(path + ": a codebook of another surface (" + shape_str(sm.shape) + " samples, this object has " +
                    std::to_string(s.n_samples()) + "); delete it to rebuild");
    b.samples = f.to_f32(sm);
    if (b.samples != s.samples) throw Error(path + ": a codebook of another surface (its samples differ); delete it to rebuild");
    b.heights = f.to_f32(h);
    for (float v : b.heights)
        if (!std::isfinite(v)) throw Error(path + ": the codebook holds a non-finite height");
    return b;
}

Codebook cached_codebook(rt::Context* ctx, const Surface& s, const CodebookOptions& o, const std::string& path) {
    if (!path.empty() && std::filesystem::exists(path)) return load_codebook(path, s, o);
    Codebook b = render_codebook(ctx, s, o);
    if (!path.empty()) save_codebook(path, b);
    return b;
}

HostTensor window_map(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, double cell_mm, double* win_mm) {
    if (H < 1 || W < 1 || depth_mm.size() != size_t(H) * size_t(W))
        throw Error("render-and-compare: the indentation map has " + std::to_string(depth_mm.size()) + " values for " +
                    std::to_string(H) + " x " + std::to_string(W) + " pixels");
    if (!(mm_per_px > 0) || !std::isfinite(mm_per_px)) throw Error("render-and-compare: mm_per_px must be positive");
    for (float v : depth_mm)
        if (!std::isfinite(v)) throw Error("render-and-compare: the indentation map holds NaN or infinity");
    const int R = std::max(1, int(std::lround(H * mm_per_px / cell_mm))), C = std::max(1, int(std::lround(W * mm_per_px / cell_mm)));
    *win_mm = H * mm_per_px / R;
    HostTensor m({R, C});
    std::vector<int> n(size_t(R * C), 0);
    for (int r = 0; r < H; ++r)
        for (int c = 0; c < W; ++c) {
            const int rr = std::min(R - 1, int((r + 0.5) * R / H)), cc = std::min(C - 1, int((c + 0.5) * C / W));
            m.data[size_t(rr * C + cc)] += std::max(0.0f, depth_mm[size_t(r * W + c)]);
            ++n[size_t(rr * C + cc)];
        }
    for (size_t k = 0; k < n.size(); ++k) m.data[k] = n[k] ? m.data[k] / float(n[k]) : 0.0f;
    return m;
}

struct CodebookScorer::Impl {
    rt::Context* ctx;
    WeightStore weights;
    std::shared_ptr<ResidentWeights> resident;
    CodebookOptions options;
    int64_t S, G, Q, NS;  // Q = G + 1: a map's quads per side
    ScoreOptions score;
    std::mutex mutex;
    using Key = std::tuple<int64_t, int64_t, double>;  // the window: R, C, cell size
    using GraphKey = std::tuple<int64_t, int64_t, double, double, bool>;  // the window, the weight, quadratic
    std::map<GraphKey, std::unique_ptr<GpuExecutor>> exec;
    std::map<GraphKey, Graph> graphs;
    uint64_t wmin_bytes = 0;
    static std::string wmin_name(const Key& k) {
        return "codebook.wmin." + std::to_string(std::get<0>(k)) + "x" + std::to_string(std::get<1>(k)) + "@" + num(std::get<2>(k));
    }
    // Each hypothesis' shallowest depth under this window: the maps, the spins and the
    // window's size fix it, so it is computed once per size and read by every touch.
    void add_window_min(const Key& k) {
        Graph g;
        g.output(ops::codebook_window_min(g, g.weight("codebook.quads", {S, 4 * Q * Q}), g.weight("codebook.spins", {NS, 2}), std::get<0>(k),
                                          std::get<1>(k), options.cell_mm, std::get<2>(k), options.cap_mm, "codebook.window_min"),
                 "wmin");
        TensorMap out = ctx ? GpuExecutor(*ctx, g, weights, resident).run({}) : run_cpu(g, weights, {});
        weights.add(wmin_name(k), std::move(out.at("wmin")));
        if (ctx) wmin_bytes += 4 * uint64_t(S) * uint64_t(NS);
    }
    Graph graph(const GraphKey& gk) const {
        Graph g;
        const auto [R, C, win, weight, quadratic] = gk;
        g.output(ops::codebook_score(g, g.weight("codebook.quads", {S, 4 * Q * Q}), g.weight("codebook.spins", {NS, 2}),
                                     g.input("measured", {R, C}), g.weight(wmin_name(Key{R, C, win}), {S * NS}), g.input("press", {1}),
                                     options.cell_mm, win, options.cap_mm, weight, quadratic, "codebook.score"),
                 "term");
        return g;
    }
};

void check_score_options(const ScoreOptions& o) {
    if (!(o.weight >= 0) || !std::isfinite(o.weight)) throw Error("render-and-compare: render_weight must be >= 0");
    if (!(o.press_percentile > 0 && o.press_percentile <= 100))
        throw Error("render-and-compare: render_press_percentile must be in (0, 100]");
    if (!(o.cell_mm >= 0.1 && o.cell_mm <= 10)) throw Error("render-and-compare: render_cell_mm must be in [0.1, 10] mm");
}

CodebookScorer::CodebookScorer(rt::Context* ctx, const Codebook& book, const Surface& s, const ScoreOptions& o)
    : impl_(std::make_unique<Impl>()) {
    if (book.samples != s.samples) throw Error("render-and-compare: the codebook was rendered for another surface");
    check_score_options(o);
    Impl& m = *impl_;
    m.ctx = ctx;
    m.options = book.options;
    m.S = s.n_samples(), m.G = book.G, m.Q = book.G + 1, m.NS = s.n_spin(), m.score = o;
    // The maps as bilinear quads (4.4x their size: one vector read per sample, the score's cost).
    m.weights.add("codebook.quads", HostTensor({m.S, 4 * m.Q * m.Q}, ops::book::quads_of_maps(book.heights.data(), m.S, int32_t(m.G), float(m.options.cap_mm))));
    m.weights.add("codebook.spins", HostTensor({m.NS, 2}, s.spins));
    if (ctx) m.resident = std::make_shared<ResidentWeights>(*ctx);
}

CodebookScorer::~CodebookScorer() = default;

std::vector<float> CodebookScorer::term(const std::vector<float>& depth_mm, int H, int W, double mm_per_px) {
    return term(depth_mm, H, W, mm_per_px, impl_->score);
}

std::vector<float> CodebookScorer::term(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, const ScoreOptions& o) {
    check_score_options(o);
    Impl& m = *impl_;
    std::lock_guard<std::mutex> lock(m.mutex);
    double win = 0;
    HostTensor meas = window_map(depth_mm, H, W, mm_per_px, o.cell_mm, &win);
    const Impl::Key key{meas.shape[0], meas.shape[1], win};  // one executor serves every touch of a sensor
    const Impl::GraphKey gk{meas.shape[0], meas.shape[1], win, o.weight, o.quadratic};
    if (!m.weights.has(Impl::wmin_name(key))) m.add_window_min(key);
    if (m.ctx && !m.exec.count(gk)) m.exec[gk] = std::make_unique<GpuExecutor>(*m.ctx, m.graph(gk), m.weights, m.resident);
    if (!m.ctx && !m.graphs.count(gk)) m.graphs.emplace(gk, m.graph(gk));
    const float press = ops::book::measured_press(meas.data.data(), int32_t(meas.data.size()), o.press_percentile);
    const TensorMap in{{"measured", meas}, {"press", HostTensor({1}, {press})}};
    TensorMap out = m.ctx ? m.exec.at(gk)->run(in) : run_cpu(m.graphs.at(gk), m.weights, in);
    return std::move(out.at("term").data);
}

uint64_t CodebookScorer::device_bytes() const {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    uint64_t arenas = 0;
    for (const auto& [k, ex] : impl_->exec) arenas += ex->memory_plan().arena_bytes + ex->memory_plan().scratch_bytes;
    return 4 * (uint64_t(impl_->S) * uint64_t(4 * impl_->Q * impl_->Q) + 2 * uint64_t(impl_->NS)) + impl_->wmin_bytes + arenas;
}

}  // namespace vtloc::track
