// vtloc::api::check and check_ops: the engine's checks (engine/check/) behind
// the public API's result structs.
#include <chrono>

#include "engine/api/api_internal.h"
#include "engine/check/device_report.h"
#include "engine/check/graph_check.h"
#include "engine/check/op_selftest.h"
#include "engine/model/tactile_encoder.h"

namespace vtloc::api {

namespace {

CheckError to_api(const check::Comparison& c) {
    CheckError e;
    e.max_abs = c.max_abs;
    e.max_rel = c.max_rel;
    e.tolerance_used = c.worst_ratio;
    e.has_indices = c.index;
    e.mismatches = c.mismatches;
    e.first_mismatch = c.detail;
    return e;
}

CheckDevice device_of(rt::Context& ctx) {
    check::DeviceReport d = check::device_report(ctx);
    return {d.name, d.type, d.vulkan, d.driver, d.limits};
}

// "tactile.layer1.0.conv1" -> "tactile.layer1"; "point.sa2.fps" -> "point.sa2"; "ilu" -> "ilu".
std::string stage_of(const std::string& node) {
    const size_t a = node.find('.');
    if (a == std::string::npos) return node;
    const std::string first = node.substr(0, a);
    if (first != "tactile" && first != "point") return first;
    const size_t b = node.find('.', a + 1);
    return b == std::string::npos ? node : node.substr(0, b);
}

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

CheckResult check(Context& context, const CheckOptions& options) {
    return guarded([&] {
        const auto t0 = std::chrono::steady_clock::now();
        rt::Context& ctx = ContextAccess::rt(context);
        CheckResult r;
        ModelInfo info;
        ModelFile file = load_checked_model(options.model, info);
        VtlocRunner runner(std::move(file.weights), std::move(file.config), &ctx);
        r.model_name = info.name;
        const TactileImage image = load_tactile_image(options.tactile);
        const HostTensor cloud = cloud_tensor(load_point_cloud(options.object, info.sample_points));
        VtlocRunner::Prepared p =
            runner.prepare_once(tactile_image_input(image.rgb.data(), image.rgb.size(), image.height, image.width), cloud, nullptr);

        const check::GraphCheck g = check::check_graph(ctx, p.graph, runner.weights(), p.inputs);
        r.device = device_of(ctx);
        r.node_tolerance = {check::kNodeTolerance.abs, check::kNodeTolerance.rel};
        r.end_to_end_tolerance = {check::kEndToEndTolerance.abs, check::kEndToEndTolerance.rel};
        for (const check::NodeCheck& n : g.nodes) {
            NodeCheck o;
            o.node = n.node;
            o.op = n.op;
            o.stage = stage_of(n.node);
            o.input_shapes.assign(n.input_shapes.begin(), n.input_shapes.end());
            o.output_shapes.assign(n.output_shapes.begin(), n.output_shapes.end());
            o.dispatches = n.dispatches;
            o.error = to_api(n.cmp);
            o.error.has_indices = n.has_index;
            o.error.indices_equal = n.indices_equal;
            o.failure = n.error;
            o.ok = n.ok();
            r.nodes.push_back(std::move(o));
        }
        for (const check::OutputCheck& out : g.outputs) {
            OutputCheck o{out.name, to_api(out.cmp), out.cmp.ok};
            o.error.indices_equal = !out.cmp.index || out.cmp.ok;
            r.outputs.push_back(std::move(o));
        }
        r.first_failure = g.first_failure;
        r.ok = g.ok();
        r.gpu_ms = g.gpu_ms;
        r.cpu_ms = g.cpu_nodes_ms + g.cpu_full_ms;
        r.wall_ms = ms_since(t0);
        return r;
    });
}

OpsCheckResult check_ops(Context& context, const std::string& filter,
                         const std::function<void(size_t, size_t, const OpCheck&)>& progress) {
    return guarded([&] {
        rt::Context& ctx = ContextAccess::rt(context);
        auto to_op = [](const check::OpCaseResult& c, const check::Tolerance& tol) {
            OpCheck o;
            o.op = c.op;
            o.variant = c.variant;
            o.dispatches = c.dispatches;
            o.error = to_api(c.cmp);
            o.error.indices_equal = !c.cmp.index || c.cmp.ok;
            o.tolerance = {tol.abs, tol.rel};
            o.failure = c.error;
            o.ok = c.ok();
            o.ms = c.ms;
            return o;
        };
        std::function<void(size_t, size_t, const check::OpCaseResult&)> step;
        if (progress)
            step = [&](size_t i, size_t n, const check::OpCaseResult& c) { progress(i, n, to_op(c, c.tol)); };
        const check::OpsCheck c = check::check_ops(ctx, filter, step);
        OpsCheckResult r;
        r.device = device_of(ctx);
        for (const check::OpCaseResult& one : c.cases) r.cases.push_back(to_op(one, one.tol));
        r.uncovered_ops = c.uncovered;
        r.ok = c.ok();
        r.wall_ms = c.ms;
        return r;
    });
}

}  // namespace vtloc::api
