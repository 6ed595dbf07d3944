// prepare_weights: the one pass at load that makes every tensor the graph
// builders read. A graph of every part (both point-branch paths, GMA, ILU,
// retrieval) finds all its weights there, and what only fed the folding is gone.
#include <catch2/catch.hpp>
#include <set>

#include "base/error.h"
#include "engine/model/gma.h"
#include "engine/model/prepared_weights.h"
#include "engine/model/vtloc_graph.h"
#include "engine/model/point_encoder.h"
#include "tests/golden.h"

using namespace vtloc;

TEST_CASE("prepared weights serve every graph shape and drop what only fed the folding", "[model][weights]") {
    for (const char* name : {"vtloc-tiny", "vtloc-mcr-tiny"}) {
        INFO(name);
        const WeightStore file = WeightStore::load(test::require_golden_file(test::goldens_dir(), std::string(name) + ".safetensors"));
        const ModelConfig cfg = config_of(file);
        const WeightStore w = prepare_weights(cfg, file);

        std::set<std::string> used;
        auto collect = [&](const Graph& g) {
            for (const Value& v : g.values())
                if (v.kind == ValueKind::Weight) {
                    REQUIRE(w.has(v.name));
                    CHECK(w.get(v.name).shape == v.shape);
                    used.insert(v.name);
                }
        };
        VtlocGraphSpec spec;
        spec.image_height = spec.image_width = 48;
        spec.n_points = 64;
        spec.n_candidates = 8;
        spec.batch = 3;
        collect(build_vtloc_graph(cfg, w, spec));
        Graph unfused;  // the point branch's other weight layout
        build_point_encoder(unfused, w, cfg, unfused.input("c", {64, cfg.point.use_normals ? 6 : 3}), {false});
        collect(unfused);

        // Nothing of the BatchNorms or the unfolded convolutions is kept; the rest of the
        // file (ILU, MCR, GMA decoder, point head) is kept as it is.
        for (const std::string& n : w.names()) {
            INFO(n);
            CHECK(n.find("running_") == std::string::npos);
            CHECK(n.find(".bn") == std::string::npos);
            CHECK(used.count(n) == 1);
            if (file.has(n)) CHECK(file.get(n).data == w.get(n).data);
        }
        CHECK(w.names().size() < file.names().size() + used.size());
    }
}

TEST_CASE("prepare_weights keeps a W^d that fits one binding whole, under its own name", "[model][weights]") {
    const WeightStore file = WeightStore::load(test::require_golden_file(test::goldens_dir(), "vtloc-tiny.safetensors"));
    const ModelConfig cfg = config_of(file);
    REQUIRE(cfg.gma);
    const WeightStore w = prepare_weights(cfg, file);
    // The tiny W^d fits one binding: it stays whole under its own name.
    CHECK(weight_row_chunks(w, "gma.weight") == std::vector<std::string>{"gma.weight"});
    CHECK(w.get("gma.weight").data == file.get("gma.weight").data);
}
