#include "base/error.h"
#include "engine/ops/ops.h"

namespace vtloc {

namespace {
const OpDef* const kOps[] = {
    &ops::op_linear,
    &ops::op_add,
    &ops::op_mul,
    &ops::op_sub,
    &ops::op_relu,
    &ops::op_leaky_relu,
    &ops::op_tanh,
    &ops::op_sigmoid,
    &ops::op_concat,
    &ops::op_conv2d,
    &ops::op_max_pool2d,
    &ops::op_global_avg_pool,
    &ops::op_tactile_preprocess,
    &ops::op_flatten,
    &ops::op_stack,
    &ops::op_rows,
    &ops::op_disentangle,
    &ops::op_gma_decode,
    &ops::op_chamfer,
    &ops::op_ilu,
    &ops::op_ilu_step,
    &ops::op_topk,
    &ops::op_heatmap,
    &ops::op_retrieve,
    &ops::op_ilu_retrieve,
    &ops::op_pose_evidence,
    &ops::op_log_softmax,
    &ops::op_spin_marginal,
    &ops::op_expected_distance,
    &ops::op_field_slack,
    &ops::op_gel_gradient,
    &ops::op_masked_poisson,
    &ops::op_mean_pool2,
    &ops::op_poisson_prolong,
    &ops::op_gel_contact_mask,
    &ops::op_codebook_render,
    &ops::op_codebook_window_min,
    &ops::op_codebook_score,
    &ops::op_fps,
    &ops::op_ball_query,
    &ops::op_point_group,
    &ops::op_group_max,
    &ops::op_group_linear,
    &ops::op_sa_gather,
    &ops::op_cloud_normalize,
    &ops::op_normal_estimate,
};
}  // namespace

const OpDef& find_op(std::string_view name) {
    for (const OpDef* op : kOps)
        if (op->name == name) return *op;
    throw Error("unknown op '" + std::string(name) + "'");
}

std::vector<std::string_view> op_names() {
    std::vector<std::string_view> out;
    for (const OpDef* op : kOps) out.push_back(op->name);
    return out;
}

}  // namespace vtloc
