#pragma once
// Render-and-compare (SPEC 9; docs/render_compare.md): what the gel would feel at
// each of the filter's hypotheses. The codebook holds one height map per surface
// sample (the object seen along the sample's axis from its point, G x G cells of
// `cell_mm`, rendered on the GPU from the surface's dense points and cached per
// object); a touch's measured indentation is scored against every hypothesis (the
// sample's map at the hypothesis' spin, pressed to the measured depth) into a log
// term the tracker multiplies in.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/ops/codebook_bins.h"
#include "engine/safetensors.h"
#include "engine/tensor.h"
#include "engine/track/surface.h"

namespace vtloc {
namespace rt {
class Context;
}
namespace track {

struct CodebookOptions {
    double cell_mm = 1.0;     // map cell
    double splat_mm = 0.75;   // a dense point covers the cells within this radius
    double cap_mm = 8;        // depths beyond +-cap are no surface (the gel cannot reach them)
    double facing = 0.3;      // points whose normal . axis exceeds this face away (back faces)
    double reach_mm = 12.5;   // the sensor window's half diagonal (15 x 20 mm): a map covers it at any spin
    double min_density = 1.0; // points per mm^2 a cloud needs (SPEC 9)
};

// The dense points binned on a coarse grid for codebook_render (engine/ops/codebook_bins.h).
using ops::book::BinnedPoints;
using ops::book::bin_points;

struct Codebook {
    static constexpr const char* kFormat = "vtloc-codebook/1";
    CodebookOptions options;
    int64_t G = 0;                // cells per side
    std::vector<float> heights;   // [S, G*G]
    std::vector<float> samples;   // [S, 9] the surface samples it was rendered for (a stale cache differs)
    int64_t n_samples() const { return int64_t(samples.size() / 9); }
};

// Throws vtloc::Error, naming its density, for a cloud too sparse to render (SPEC 9): the
// codebook and the renders at exact poses (pose_shape.h) both splat its points.
void check_render_density(const Surface& s, const CodebookOptions& o);
// Renders every sample's map (ctx null: the op's CPU reference). Throws
// vtloc::Error for a cloud too sparse to render (SPEC 9), naming its density.
Codebook render_codebook(rt::Context* ctx, const Surface& s, const CodebookOptions& o = {});
// The maps of some samples ([rows.size(), G*G]; rows index the surface's samples), rendered as
// render_codebook renders them: a codebook's spot check (check_tracker).
std::vector<float> render_codebook_rows(rt::Context* ctx, const Surface& s, const std::vector<int64_t>& rows, const CodebookOptions& o = {});
// The cache: a safetensors file with the format, the options, the maps and the samples.
void save_codebook(const std::string& path, const Codebook& b);
// Throws vtloc::Error naming the path for another format or version, a malformed
// file, or a codebook of another surface or options (stale: delete it to rebuild).
Codebook load_codebook(const std::string& path, const Surface& s, const CodebookOptions& o = {});
// The same on a parsed file (`path` names it in errors; the fuzz target's entry).
Codebook parse_codebook(const SafetensorsFile& f, const std::string& path, const Surface& s, const CodebookOptions& o = {});
// load_codebook where `path` exists and holds this surface's, else render and save
// (path empty: render only).
Codebook cached_codebook(rt::Context* ctx, const Surface& s, const CodebookOptions& o, const std::string& path);

// A measured indentation (H x W, mm_per_px) averaged onto the comparison window's
// cells of about `cell_mm`: [R, C] and the exact cell size (R = round(H mm_per_px / cell)).
HostTensor window_map(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, double cell_mm, double* win_mm);

// How a touch is scored (docs/render_compare.md; fitted on training touches and windows).
struct ScoreOptions {
    double weight = 0.25;           // the term's inverse temperature
    bool quadratic = true;          // the error also loses its r^2, c^2, r c fit (the reader's bowl)
    double press_percentile = 70;   // the measured press: this percentile of the pressed cells
    double cell_mm = 3.0;           // the comparison window's cells (the maps keep their 1 mm; fitted: 3 mm as good as 1, 9x fewer reads)
};

// Throws vtloc::Error naming the bad option by its api::TrackerOptions name (render_weight,
// render_press_percentile, render_cell_mm): the tracker checks at construction, the scorer when made.
void check_score_options(const ScoreOptions& o);

// Scores touches against a codebook on the GPU (ctx null: the CPU reference). One scorer
// serves any score options (the trackers with_options makes of one object share it, the
// maps on the device once), from several threads: each call takes its lock.
class CodebookScorer {
public:
    CodebookScorer(rt::Context* ctx, const Codebook& book, const Surface& s, const ScoreOptions& o);
    ~CodebookScorer();
    // The log term over the hypotheses [S * NS] for one touch's indentation, scored as the
    // constructor's options say, or as `o` says.
    std::vector<float> term(const std::vector<float>& depth_mm, int H, int W, double mm_per_px);
    std::vector<float> term(const std::vector<float>& depth_mm, int H, int W, double mm_per_px, const ScoreOptions& o);
    uint64_t device_bytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace track
}  // namespace vtloc
