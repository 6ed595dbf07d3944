#pragma once
// The point branch of SPEC section 2: PointNet++ set abstraction (MSG, or SSG
// with one scale per stage), a group-all stage and the MLP head, giving F^p.
// Every number comes from the config (weight-file metadata "point" and "C").
#include <string>
#include <utility>
#include <vector>

#include "engine/graph.h"
#include "engine/model/model_config.h"
#include "engine/tensor.h"
#include "engine/weights.h"

namespace vtloc {

namespace rt {
struct DeviceInfo;  // runtime/context.h: the layout rule reads only its type
}

struct PointEncoderOutputs {
    int feature = -1;  // F^p, [1, C]
    // SPEC 8 names -> I32 index values: {"point.sa1.fps", id}, {"point.sa1.ball.0", id}, ...
    std::vector<std::pair<std::string, int>> indices;
};

struct PointEncoderOptions {
    // Fused: neighbour gather inside the first MLP layer's GEMM and the max over
    // neighbours inside the last. Unfused (false): point_group, linear, group_max
    // as separate nodes; the same numbers, kept as a cross-check.
    bool fuse = true;
    // Fused only: ball padding (a ball's free slots, which repeat its first point)
    // left out of the work, exactly (docs/performance.md "Ball padding"); false computes every
    // row (vtloc-bench-point's A/B).
    bool skip_padding = true;
    // Fused only: a scale's layers pass their rows point-major ([M, C]) instead of
    // channel-major ([C, M]); faster on lavapipe (docs/performance.md "Point-major rows").
    // The model takes point_major_rows_on(its device).
    bool point_major_rows = true;
    // > 0: a set-abstraction layer's tiles as a GPU shrinks them to offer this many
    // workgroups (GroupLinear::fill; vtloc-bench-point's sweep on GPUs).
    int64_t fill = 0;
};

// The rows' layout the model takes on a device (null: the CPU reference): point-major on
// CPU drivers, channel-major on GPUs, where it took an H200's point MLPs 11-15 % less
// time (2026-12-04, vtloc-bench-point's layout A/B at 1,024-16,384 points).
bool point_major_rows_on(const rt::DeviceInfo* device);

// cloud: [N, 6] (xyz + normals) when config point.use_normals, else [N, 3], in
// the normalised frame (object_frame.h). Reads `point.sa{i}.conv_blocks.*`,
// `bn_blocks.*`, `point.sa{n+1}.mlp_convs.*`, `mlp_bns.*` and `point.mlp.*`;
// as prepare_weights left them: each BatchNorm folded into its 1x1 convolution,
// `<conv>.weight#bn#kn` ([in, out], group_linear's layout), `<conv>.weight#bn#2d`
// ([out, in], linear's, for the unfused path) and `<conv>.bias#bn`.
// Fused graph per scale: fps, ball_query, group_linear (gather) -> group_linear
// ... -> group_linear (max); scales concatenated; group all: group_linear on
// [xyz, features] -> ... -> group_max; then the point.mlp head (linear).
// Throws vtloc::Error on a config that does not fit the schema, a cloud of the
// wrong width, or fewer points than a stage samples.
PointEncoderOutputs build_point_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int cloud);
PointEncoderOutputs build_point_encoder(Graph& g, const WeightStore& w, const ModelConfig& config, int cloud,
                                        const PointEncoderOptions& options);

// The one host-side check of an object cloud before the point branch runs
// (shaders cannot throw; VtlocRunner calls it): [N, 6] (xyz and normals,
// whichever columns the config feeds the encoder), finite values, at least
// sa1's npoint points. Throws vtloc::Error naming the problem.
void check_object_cloud(const HostTensor& cloud, const ModelConfig& config);

}  // namespace vtloc
