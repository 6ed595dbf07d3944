// Self-test cases: linear, the binary and activation ops, concat, flatten, stack, rows
// (the shapes of tests/test_ops.cpp).
#include <cmath>

#include "engine/check/op_selftest.h"
#include "engine/ops/common.h"
#include "engine/ops/build.h"

namespace vtloc::check {

namespace {

OpCase linear_case(const Shape& x, int64_t out, bool bias, uint32_t act, uint32_t seed, const std::string& why) {
    OpCase c("linear", why + ": x" + shape_str(x) + " -> " + std::to_string(out) + (bias ? "" : ", no bias") +
                           (act ? ", act " + std::to_string(act) : ""));
    const int64_t in = x.back();
    const float bound = 1.0f / std::sqrt(float(std::max<int64_t>(1, in)));
    const int xv = c.input("x", random_tensor(x, seed, -2.0f, 2.0f));
    const int wv = c.weight("w", random_tensor({out, in}, seed + 1, -bound, bound));
    const int bv = bias ? c.weight("b", random_tensor({out}, seed + 2, -bound, bound)) : -1;
    c.output(ops::linear(c.g, xv, wv, bv, ops::Act(act), 0.2), "y");
    return c;
}

}  // namespace

std::vector<OpCase> dense_cases(const rt::DeviceInfo&) {
    std::vector<OpCase> v;
    v.push_back(linear_case({1, 513}, 300, true, ops::kActNone, 3, "one row (short-M tile)"));
    v.push_back(linear_case({5, 127, 33}, 65, true, ops::kActNone, 2, "odd shape"));
    v.push_back(linear_case({7, 1}, 3, true, ops::kActNone, 4, "K = 1"));
    v.push_back(linear_case({130, 70}, 129, false, ops::kActLeaky, 6, "several tiles, ragged edges"));
    v.push_back(linear_case({9, 31}, 17, true, ops::kActSigmoid, 14, "fused activation"));

    for (const char* op : {"add", "sub", "mul"})
        for (const Shape& b : {Shape{5, 127, 33}, Shape{33}}) {
            OpCase c(op, "[5, 127, 33] with " + shape_str(b) + (b.size() < 3 ? " (broadcast)" : ""));
            int x = c.input("a", random_tensor({5, 127, 33}, 30)), y = c.input("b", random_tensor(b, 31));
            c.output(c.g.add1(op, {x, y}), "y");
            v.push_back(std::move(c));
        }
    for (const char* op : {"relu", "leaky_relu", "tanh", "sigmoid"})
        for (float range : {3.0f, 60.0f}) {
            const Shape s = range < 10 ? Shape{5, 127, 33} : Shape{1000};
            OpCase c(op, shape_str(s) + " in +-" + std::to_string(int(range)) + (range > 10 ? " (saturation)" : ""));
            c.output(c.g.add1(op, {c.input("x", random_tensor(s, 20, -range, range))}, {{"slope", 0.05}}), "y");
            v.push_back(std::move(c));
        }

    // 2-d concats along the last axis: inputs of `rows` x widths[i], seeds from `seed`.
    auto concat_case = [](const std::string& why, int64_t rows, std::vector<int64_t> widths, uint32_t seed) {
        OpCase c("concat", why);
        std::vector<int> parts;
        for (size_t i = 0; i < widths.size(); ++i)
            parts.push_back(c.input(std::string("x").append(std::to_string(i)), random_tensor({rows, widths[i]}, seed + uint32_t(i))));
        c.output(c.g.add1("concat", parts), "y");
        return c;
    };
    v.push_back(concat_case("[127, 33] [127, 64] [127, 5] [127, 2] along the last axis", 127, {33, 64, 5, 2}, 40));
    v.push_back(concat_case("[300, 64] [300, 128] [300, 8]: vec4 columns, more rows than row groups", 300, {64, 128, 8}, 46));
    OpCase cat3("concat", "[5, 7, 3] [5, 7, 1] (3-d, one column)");
    cat3.output(cat3.g.add1("concat", {cat3.input("a", random_tensor({5, 7, 3}, 44)),
                                       cat3.input("b", random_tensor({5, 7, 1}, 45))}),
                "y");
    v.push_back(std::move(cat3));

    OpCase flat("flatten", "[3, 5, 7, 9] -> [3, 315] (a copy, no shader)");
    flat.output(flat.g.add1("flatten", {flat.input("x", random_tensor({3, 5, 7, 9}, 50))}), "y");
    v.push_back(std::move(flat));

    OpCase st("stack", "[1, 3, 5, 7] [2, 3, 5, 7] [1, 3, 5, 7] along the first axis (copies, no shader)");
    st.output(st.g.add1("stack", {st.input("a", random_tensor({1, 3, 5, 7}, 51)), st.input("b", random_tensor({2, 3, 5, 7}, 52)),
                                  st.input("c", random_tensor({1, 3, 5, 7}, 53))}),
              "y");
    v.push_back(std::move(st));
    OpCase rw("rows", "rows 2..4 of [7, 3, 5] (a copy, no shader)");
    rw.output(rw.g.add1("rows", {rw.input("x", random_tensor({7, 3, 5}, 54))}, {{"start", 2}, {"count", 3}}), "y");
    v.push_back(std::move(rw));
    return v;
}

}  // namespace vtloc::check
