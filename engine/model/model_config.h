#pragma once
// The model config (a weight file's __metadata__["vtloc.config"], SPEC section 7)
// as one typed, validated struct. It is parsed once, where a weight file is
// loaded; graph builders, the runner, the API and the bench read this struct,
// never the JSON.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/ops/ops.h"
#include "engine/ops/tactile_preprocess.h"
#include "engine/weights.h"

namespace vtloc {

// Run-time limits of every model, defined once here (the ops' own where an op
// imposes them).
namespace limits {
inline constexpr int kMaxIters = 64;                         // ILU: N in 0..64 per run
inline constexpr int64_t kMaxTopK = ops::kMaxTopK;           // top-K op
inline constexpr int64_t kMinImageSide = ops::kMinTactileSide;  // tactile_preprocess op
}  // namespace limits

struct TactileConfig {
    int64_t crop = 0, in_size = 0;
    std::vector<int64_t> widths, blocks, mlp;  // 4 stage widths, 4 block counts, head hidden sizes
};

struct SaStageConfig {
    int64_t npoint = 0;
    std::vector<double> radii;               // one per scale
    std::vector<int64_t> nsample;            // one per scale
    std::vector<std::vector<int64_t>> mlps;  // one per scale
};

struct PointConfig {
    int64_t n_points = 0;  // points sampled from a surface for this model
    bool use_normals = true;
    std::vector<SaStageConfig> sa;
    std::vector<int64_t> group_all, mlp;
    int64_t cloud_width() const { return use_normals ? 6 : 3; }
    int64_t min_points() const { return sa.front().npoint; }  // the first stage samples this many
};

struct GmaConfig {
    int64_t n_points = 0, channels = 0;
    std::vector<int64_t> decoder;
};

struct SensorConfig {
    double mm_per_px = 0;
    int64_t height = 0, width = 0;
};

enum class Head { Ilu, Mcr };

struct ModelConfig {
    std::string name;
    int64_t C = 0, K = 0;
    TactileConfig tactile;
    PointConfig point;
    std::optional<GmaConfig> gma;
    Head head = Head::Ilu;
    int ilu_iters = 0;             // head == Ilu
    int64_t ilu_head_hidden = 0;   // head == Ilu
    std::vector<int64_t> mcr_hidden;  // head == Mcr
    std::optional<SensorConfig> sensor;
    nlohmann::json source_json;    // as read, for reports and metadata

    // Validates the whole schema; throws vtloc::Error "<source>: model config:
    // '<key>' <problem>", naming the first offending key.
    static ModelConfig parse(const nlohmann::json& j, const std::string& source);
    const char* head_name() const { return head == Head::Ilu ? "ilu" : "mcr"; }
};

// The config of a loaded weight store, parsed (errors name the store's file).
inline ModelConfig config_of(const WeightStore& w) { return ModelConfig::parse(w.config(), w.source()); }

}  // namespace vtloc
