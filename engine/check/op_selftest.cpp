#include "engine/check/op_selftest.h"

#include <chrono>
#include <random>
#include <set>

#include "engine/check/graph_check.h"
#include "engine/op.h"
#include "runtime/context.h"

namespace vtloc::check {

int OpCase::input(const std::string& name, HostTensor t) {
    const int id = g.input(name, t.shape, t.type);
    in[name] = std::move(t);
    return id;
}

int OpCase::weight(const std::string& name, HostTensor t) {
    const Shape s = t.shape;
    w.add(name, std::move(t));
    return g.weight(name, s);
}

HostTensor random_tensor(const Shape& shape, uint32_t seed, float lo, float hi) {
    HostTensor t(shape);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(lo, hi);
    for (float& v : t.data) v = u(rng);
    return t;
}

bool OpsCheck::ok() const {
    if (!uncovered.empty() || cases.empty()) return false;
    for (const OpCaseResult& c : cases)
        if (!c.ok()) return false;
    return true;
}

namespace {

OpCaseResult run_case(rt::Context& ctx, const OpCase& c) {
    OpCaseResult r;
    r.op = c.op;
    r.variant = c.variant;
    r.tol = c.tol;
    const auto t0 = std::chrono::steady_clock::now();
    try {
        GpuExecutor exec(ctx, c.g, c.w);
        TensorMap got = exec.run(c.in);
        for (const rt::Sequence::DispatchRecord& d : exec.sequence().dispatch_log())
            r.dispatches.push_back(dispatch_str(d.shader, d.spec, d.texel_bindings, d.groups));
        TensorMap want = run_cpu(c.g, c.w, c.in);
        for (auto& [name, t] : want) {
            Comparison one = compare(got.at(name), t, c.tol);
            if (!one.ok) one.detail = name + " " + one.detail;
            merge(r.cmp, one);
        }
    } catch (const std::exception& e) {
        r.error = e.what();
    }
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace

OpsCheck check_ops(rt::Context& ctx, const std::string& filter,
                   const std::function<void(size_t, size_t, const OpCaseResult&)>& progress) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<OpCase> all;
    for (auto family : {dense_cases, image_cases, point_cases, head_cases, track_cases, gel_cases, codebook_cases})
        for (OpCase& c : family(ctx.info())) all.push_back(std::move(c));
    OpsCheck r;
    std::set<std::string> covered;
    for (const OpCase& c : all) covered.insert(c.op);
    for (std::string_view op : op_names())
        if (!covered.count(std::string(op)) && std::string(op).find(filter) != std::string::npos)
            r.uncovered.emplace_back(op);
    std::vector<const OpCase*> todo;
    for (const OpCase& c : all)
        if (c.op.find(filter) != std::string::npos) todo.push_back(&c);
    for (size_t i = 0; i < todo.size(); ++i) {
        r.cases.push_back(run_case(ctx, *todo[i]));
        if (progress) progress(i, todo.size(), r.cases.back());
    }
    r.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return r;
}

}  // namespace vtloc::check
