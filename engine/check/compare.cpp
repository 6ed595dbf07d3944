#include "engine/check/compare.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace vtloc::check {

namespace {

std::string element_str(const HostTensor& t, int64_t i) {
    std::ostringstream s;
    s.precision(9);
    if (t.type == ElemType::I32) s << t.int_at(size_t(i));
    else s << t.data[size_t(i)];
    return s.str();
}

}  // namespace

Comparison compare(const HostTensor& gpu, const HostTensor& cpu, Tolerance tol) {
    Comparison c;
    c.index = cpu.type == ElemType::I32;
    if (gpu.shape != cpu.shape || gpu.type != cpu.type || gpu.data.size() != cpu.data.size()) {
        c.ok = false;
        c.mismatches = 1;
        c.first_bad = 0;
        c.worst_ratio = INFINITY;
        c.detail = "GPU " + shape_str(gpu.shape) + " " + elem_type_name(gpu.type) + " vs CPU " + shape_str(cpu.shape) +
                   " " + elem_type_name(cpu.type);
        return c;
    }
    for (size_t i = 0; i < cpu.data.size(); ++i) {
        bool bad = false;
        if (c.index) {
            const int64_t g = gpu.int_at(i), r = cpu.int_at(i);
            if (g != r) {
                bad = true;
                c.max_abs = std::max(c.max_abs, double(std::llabs(g - r)));
                c.worst_ratio = INFINITY;
            }
        } else {
            const double g = gpu.data[i], r = cpu.data[i];
            if (std::isnan(g) || std::isnan(r)) {
                bad = std::isnan(g) != std::isnan(r);
                if (bad) c.max_abs = c.worst_ratio = INFINITY;
            } else {
                const double d = g == r ? 0.0 : std::abs(g - r);  // inf == inf is exact
                const double allowed = tol.abs + tol.rel * std::abs(r);
                const double ratio = d == 0 ? 0.0 : allowed > 0 ? d / allowed : INFINITY;  // tolerance 0: exact
                c.max_abs = std::max(c.max_abs, d);
                if (std::abs(r) > tol.abs) c.max_rel = std::max(c.max_rel, d / std::abs(r));
                c.worst_ratio = std::max(c.worst_ratio, ratio);
                bad = !(ratio <= 1.0);
            }
        }
        if (!bad) continue;
        c.ok = false;
        if (c.mismatches++ == 0) {
            c.first_bad = int64_t(i);
            c.detail = "element " + std::to_string(i) + ": GPU " + element_str(gpu, int64_t(i)) + ", CPU " +
                       element_str(cpu, int64_t(i));
        }
    }
    return c;
}

void merge(Comparison& a, const Comparison& b) {
    a.index = a.index || b.index;
    a.max_abs = std::max(a.max_abs, b.max_abs);
    a.max_rel = std::max(a.max_rel, b.max_rel);
    a.worst_ratio = std::max(a.worst_ratio, b.worst_ratio);
    if (a.ok && !b.ok) {
        a.first_bad = b.first_bad;
        a.detail = b.detail;
    }
    a.ok = a.ok && b.ok;
    a.mismatches += b.mismatches;
}

}  // namespace vtloc::check
