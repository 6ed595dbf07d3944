#pragma once
// Every op the engine has; registry.cpp lists them by name.
#include <cstdint>

#include "engine/op.h"

namespace vtloc::ops {

// The top-K op sorts at most this many keys per chunk pass (shared-memory bound).
inline constexpr int64_t kMaxTopK = 256;

// Loop iterations of the one invocation that scans in topk_subgroup.comp (M
// candidates) and heatmap_subgroup.comp (P points, T symmetry maps), held to
// kLoopIterationBudget; retrieve_subgroup.comp runs both scans (topk.cpp, heatmap.cpp).
uint64_t topk_subgroup_iterations(int64_t M, int64_t K, uint32_t subgroup);
uint64_t heatmap_subgroup_iterations(int64_t P, int64_t K, int64_t T, uint32_t subgroup);

extern const OpDef op_linear;      // linear.cpp
extern const OpDef op_add;         // binary.cpp
extern const OpDef op_mul;         // binary.cpp
extern const OpDef op_sub;         // binary.cpp
extern const OpDef op_relu;        // activation.cpp
extern const OpDef op_leaky_relu;  // activation.cpp
extern const OpDef op_tanh;        // activation.cpp
extern const OpDef op_sigmoid;     // activation.cpp
extern const OpDef op_concat;      // concat.cpp
extern const OpDef op_conv2d;              // conv2d.cpp
extern const OpDef op_max_pool2d;          // pool2d.cpp
extern const OpDef op_global_avg_pool;     // pool2d.cpp
extern const OpDef op_tactile_preprocess;  // tactile_preprocess.cpp
extern const OpDef op_flatten;             // flatten.cpp
extern const OpDef op_stack;               // stack.cpp
extern const OpDef op_rows;                // rows.cpp
extern const OpDef op_disentangle;  // disentangle.cpp (GMA)
extern const OpDef op_gma_decode;   // gma_decode.cpp
extern const OpDef op_chamfer;      // chamfer.cpp
extern const OpDef op_ilu;          // ilu.cpp
extern const OpDef op_ilu_step;     // ilu_step.cpp
extern const OpDef op_topk;         // topk.cpp
extern const OpDef op_heatmap;      // heatmap.cpp
extern const OpDef op_retrieve;     // retrieve.cpp (topk + heatmap)
extern const OpDef op_ilu_retrieve; // ilu_retrieve.cpp (ilu + retrieve)
extern const OpDef op_pose_evidence;     // pose_evidence.cpp (multi-touch filter)
extern const OpDef op_log_softmax;       // log_softmax.cpp
extern const OpDef op_gel_gradient;      // gel_shape.cpp (the gel's shape from a frame)
extern const OpDef op_masked_poisson;    // gel_shape.cpp
extern const OpDef op_mean_pool2;        // mean_pool2.cpp
extern const OpDef op_poisson_prolong;   // poisson_prolong.cpp
extern const OpDef op_gel_contact_mask;  // gel_contact_mask.cpp
extern const OpDef op_codebook_render;   // codebook.cpp (render-and-compare)
extern const OpDef op_codebook_window_min;  // codebook.cpp
extern const OpDef op_codebook_score;    // codebook.cpp
extern const OpDef op_spin_marginal;     // pose_reduce.cpp
extern const OpDef op_expected_distance; // pose_reduce.cpp
extern const OpDef op_field_slack;       // field_slack.cpp
extern const OpDef op_fps;              // fps.cpp (point cloud)
extern const OpDef op_ball_query;       // ball_query.cpp
extern const OpDef op_point_group;      // point_group.cpp
extern const OpDef op_group_max;        // point_group.cpp
extern const OpDef op_group_linear;     // group_linear.cpp
extern const OpDef op_sa_gather;     // sa_gather.cpp
extern const OpDef op_cloud_normalize;  // cloud_normalize.cpp
extern const OpDef op_normal_estimate;  // normal_estimate.cpp
}  // namespace vtloc::ops
