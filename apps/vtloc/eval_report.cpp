// vtloc eval: the table (stdout, markdown) and the JSON / CSV reports (docs/eval.md).
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/vtloc/eval.h"
#include "engine/sim/dataset.h"

namespace vtloc::cli::eval {

namespace {

const char* cloud_label(const std::string& cloud) {
    return cloud == "full" ? "full clouds with normals"
                           : cloud == "xyz" ? "full clouds, normals estimated" : "single-view clouds, normals estimated";
}


const char* kSubsets[] = {"non-uniform", "uniform", "all"};

void write_text(const std::string& path, const std::string& text) {
    try {
        sim::write_file_atomic(path, text);
    } catch (const std::exception& e) {
        throw api::Error(e.what());
    }
}

std::string fmt(const char* f, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

// A table cell: "-" for a row without objects.
std::string cell(const char* f, double v, bool none) { return none ? "-" : fmt(f, v); }

std::string method_label(const Row& r) { return r.label.empty() ? r.method : r.label; }

}  // namespace

std::vector<Row> make_rows(const MethodResult& r, const std::vector<Job>& jobs) {
    std::vector<Row> rows;
    if (r.skipped) return rows;
    for (const char* subset : kSubsets) {
        std::vector<std::vector<sim::TouchScore>> part;
        for (size_t j = 0; j < jobs.size(); ++j)
            if (std::string(subset) == "all" || jobs[j].rec->subset == subset) part.push_back(r.scores[j]);
        rows.push_back(Row{r.method, r.label, subset, r.note, sim::aggregate(part)});  // no objects: null metrics
    }
    return rows;
}

void print_table(const Report& rep) {
    size_t width = 6;
    for (const Row& r : rep.rows) width = std::max(width, method_label(r).size());
    std::printf("%-*s  %-11s  %7s  %7s  %8s  %6s  %9s  %9s  %6s\n", int(width), "method", "subset", "objects", "touches",
                "mm Error", "ND (%)", "Top-1 (%)", "Top-5 (%)", "MPE");
    for (const Row& r : rep.rows) {
        const bool none = r.m.objects == 0;
        std::printf("%-*s  %-11s  %7d  %7d  %8s  %6s  %9s  %9s  %6s\n", int(width), method_label(r).c_str(),
                    r.subset.c_str(), r.m.objects, r.m.touches, cell("%.2f", r.m.mm, none).c_str(),
                    cell("%.2f", r.m.nd, none).c_str(), cell("%.1f", r.m.top1, none).c_str(),
                    cell("%.1f", r.m.top5, none).c_str(), cell("%.3f", r.m.mpe, none).c_str());
    }
    for (const std::string& n : rep.notes) std::printf("%s\n", n.c_str());
    if (rep.opt.cloud != "full") std::printf("object clouds: %s\n", cloud_label(rep.opt.cloud));
    std::printf("engine time %.2f ms per touch (%s; warm: each new batch shape ran once untimed)\n",
                rep.time_per_touch_ms, rep.head == "mcr" ? "MCR head" : (std::to_string(rep.iters) + " ILU iterations").c_str());
}

void write_markdown(const std::string& path, const Report& rep) {
    std::ostringstream md;
    md << "| Method | Subset | Objects | Touches | mm Error | ND (%) | Top-1 (%) | Top-5 (%) | MPE |\n"
       << "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
    for (const Row& r : rep.rows) {
        // The model rows carry the paper's method name (VTLoc / MCR by the head) and the config.
        const bool none = r.m.objects == 0;
        std::string label = method_label(r);
        if (r.method == rep.config) label = (rep.head == "mcr" ? "MCR (" : "VTLoc (") + rep.config + ")";
        md << "| " << label << " | " << r.subset << " | " << r.m.objects << " | " << r.m.touches << " | "
           << cell("%.2f", r.m.mm, none) << " | " << cell("%.2f", r.m.nd, none) << " | "
           << cell("%.1f", r.m.top1, none) << " | " << cell("%.1f", r.m.top5, none) << " | "
           << cell("%.3f", r.m.mpe, none) << " |\n";
    }
    md << "\n" << rep.opt.split << " touches, " << rep.opt.objects << " objects, " << rep.iters
       << " ILU iterations, " << cloud_label(rep.opt.cloud)
       << ", top-" << rep.opt.topk
       << "; " << fmt("%.2f", rep.time_per_touch_ms) << " ms engine time per touch.\n";
    for (const std::string& n : rep.notes) md << "\n" << n << "\n";
    for (const std::string& w : rep.warnings) md << "\n**" << w << "**\n";
    write_text(path, md.str());
}

void write_json(const std::string& path, const Report& rep, const MethodResult& model, const std::vector<Job>& jobs) {
    nlohmann::json rows = nlohmann::json::array();
    for (const Row& r : rep.rows) {
        auto v = [&](double x) { return r.m.objects ? nlohmann::json(x) : nlohmann::json(nullptr); };
        nlohmann::json j{{"method", r.method}, {"subset", r.subset}, {"objects", r.m.objects}, {"touches", r.m.touches},
                         {"mm", v(r.m.mm)},      {"nd", v(r.m.nd)},      {"top1", v(r.m.top1)},    {"top5", v(r.m.top5)},
                         {"mpe", v(r.m.mpe)}};
        if (!r.note.empty()) j["note"] = r.note;
        rows.push_back(j);
    }
    nlohmann::json per_touch = nlohmann::json::array();
    for (const TouchRow& t : model.rows)
        per_touch.push_back({{"object", jobs[t.job].rec->name}, {"touch", t.touch->id}, {"subset", jobs[t.job].rec->subset},
                             {"error_mm", t.m.error_mm}, {"nd", t.m.nd}, {"rank", t.m.rank}, {"mpe", t.m.mpe},
                             {"contact", {t.contact[0], t.contact[1], t.contact[2]}}});
    nlohmann::json skipped = nlohmann::json::array();
    for (const Skip& s : rep.skips)
        skipped.push_back({{"object", s.object}, {"touch", s.touch}, {"file", s.file}, {"reason", s.reason}});
    nlohmann::json j{{"format", "vtloc-eval/1"},
                     {"model", rep.opt.model},
                     {"config", rep.config},
                     {"data", rep.opt.data},
                     {"split", rep.opt.split},
                     {"objects", rep.opt.objects},
                     {"iters", rep.head == "mcr" ? nlohmann::json(nullptr) : nlohmann::json(rep.iters)},
                     {"topk", rep.opt.topk},
                     {"sequence", 1},  // single touches; several: vtloc eval --sequence (its own report)
                     {"cloud", rep.opt.cloud},
                     {"mm_per_px", rep.opt.frames_mm_per_px ? nlohmann::json(*rep.opt.frames_mm_per_px)
                                                            : nlohmann::json(nullptr)},
                     {"backend", rep.opt.backend == api::Backend::Gpu ? "gpu" : "cpu"},
                     {"rows", rows},
                     {"per_touch", per_touch},
                     {"skipped", skipped},
                     {"notes", rep.notes},
                     {"warnings", rep.warnings},
                     {"time_per_touch_ms", rep.time_per_touch_ms}};
    write_text(path, j.dump(2) + "\n");
}

void write_per_touch_csv(const std::string& path, const MethodResult& model, const std::vector<Job>& jobs) {
    std::ostringstream csv;
    csv << "object,touch,subset,error_mm,nd,rank,mpe\n";
    char buf[160];
    for (const TouchRow& t : model.rows) {
        std::snprintf(buf, sizeof buf, ",%d,%s,%.9g,%.9g,%d,%.9g\n", t.touch->id, jobs[t.job].rec->subset.c_str(),
                      t.m.error_mm, t.m.nd, t.m.rank, t.m.mpe);
        csv << jobs[t.job].rec->name << buf;
    }
    write_text(path, csv.str());
}

}  // namespace vtloc::cli::eval
