#pragma once
// The whole VTLoc network of SPEC sections 2-3 as one graph, built from the
// weight file's config: tactile preprocessing + encoder, PointNet++, GMA +
// Chamfer (optional), ILU or MCR, top-K retrieval and the heat-map. One graph
// is one command buffer, so a run is one submit.
//
// A batch of B > 1 touches on one object runs as one network: each per-touch
// input and output (touch_outputs() below) gains a leading axis B; B = 1 keeps
// the SPEC section 8 shapes.
// Inputs:
//   tactile.image      I32 [H, W, 3] byte values (ops::tactile_image_tensor); [B, H, W, 3]
//   point.cloud        F32 [N, 6] (or [N, 3] without normals), normalised frame
//   gma.target         F32 [N, 6] normalised cloud with normals, only when GMA
//                      runs and the network takes no normals
//   point.feature      F32 [1, C] instead of point.cloud when the object is cached
//   candidates         F32 [M, 3] normalised, when retrieval is on
//   ilu.iters          I32 [1], N for this run (ILU head only)
//   symmetry           F32 [order, 12] (engine/model/post.h), with a symmetry prior
// Outputs: the SPEC section 8 names, plus point.feature when the object branch
//   runs; ilu.c is [max_iters, 3] of which the first N rows are c_1..c_N.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/model/model_config.h"
#include "engine/weights.h"

namespace vtloc {

struct VtlocGraphSpec {
    int64_t image_height = 0, image_width = 0;  // 0: no tactile branch (encode an object only)
    int64_t batch = 1;                          // touches in one graph (all on one object)
    int64_t n_points = 0;                       // object cloud size
    bool encode_object = true;                  // false: point.feature is an input
    int64_t n_candidates = 0;                   // 0: no retrieval
    int64_t k = 0;                              // top-K size; 0: the config's K
    bool gma = true;                            // run GMA (if the model has it)
    int max_iters = limits::kMaxIters;                        // ILU: N may be 0..max_iters per run
    int symmetry_order = 0;                     // > 1: heat-map with the symmetry prior
    bool ilu_stepped = false;                   // bench: one dispatch per ILU iteration (build_ilu_stepped)
    bool retrieval_apart = false;               // bench: ILU and retrieval as nodes of their own (ilu, retrieve)
    bool point_major_rows = true;               // PointEncoderOptions's; VtlocRunner: point_major_rows_on
};

// Builds the graph from weights made by prepare_weights (engine/model/prepared_weights.h).
Graph build_vtloc_graph(const ModelConfig& config, const WeightStore& w, const VtlocGraphSpec& spec);

// The outputs with one row per touch (a leading axis B in a batch graph).
// keeps_axis: the single-touch graph gives them a leading axis of 1 too
// (tactile.input [1, 3, S, S], tactile.feature [1, C], gma.cloud [1, N^d, 6]).
struct TouchOutput {
    const char* name;
    bool keeps_axis;
};
const std::vector<TouchOutput>& touch_outputs();

}  // namespace vtloc
