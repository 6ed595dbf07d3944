#include "bench/stages.h"

namespace vtloc::bench {

namespace {
bool starts(const std::string& s, const char* p) { return s.rfind(p, 0) == 0; }
}  // namespace

const std::vector<std::string>& stage_names() {
    static const std::vector<std::string> names{"preprocess", "tactile", "point", "gma", "head", "retrieval"};
    return names;
}

std::string stage_of(const std::string& op, const std::string& n) {
    if (op == "tactile_preprocess") return "preprocess";
    if (starts(n, "tactile.")) return "tactile";
    if (starts(n, "point.")) return "point";
    if (starts(n, "gma.")) return "gma";
    if (starts(n, "ilu") || starts(n, "mcr.")) return "head";
    if (op == "topk" || op == "heatmap" || op == "retrieve") return "retrieval";
    return "other";
}

}  // namespace vtloc::bench
