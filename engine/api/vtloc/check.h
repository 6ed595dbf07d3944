#pragma once
// VTLoc's device check (`vtloc check`), part of the public API: included by
// <vtloc/vtloc.h>, installed beside it. Standard library only, like vtloc.h.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace vtloc::api {

class Context;  // <vtloc/vtloc.h>

// ---- Checking a device against the CPU reference (`vtloc check`) ------------

struct CheckTolerance {
    double abs = 0, rel = 0;  // |gpu - cpu| <= abs + rel * |cpu|; index tensors compare exactly
};

// The errors of one comparison (a node's outputs, one op case, or one output).
struct CheckError {
    double max_abs = 0;          // max |gpu - cpu|
    double max_rel = 0;          // max |gpu - cpu| / |cpu| where |cpu| > the absolute tolerance
    double tolerance_used = 0;   // max |gpu - cpu| / (abs + rel * |cpu|); above 1 fails
    bool has_indices = false;    // some output is an I32 index tensor
    bool indices_equal = true;   // ... and all of them equal the reference
    int64_t mismatches = 0;      // elements out of tolerance
    std::string first_mismatch;  // "element i: GPU x, CPU y", when there is one
};

struct NodeCheck {
    std::string node, op;
    std::string stage;           // the node name's first part ("tactile", "point.sa1", "ilu", ...)
    std::vector<std::vector<int64_t>> input_shapes, output_shapes;
    std::vector<std::string> dispatches;  // "shader spec=[local size, constants...] groups=XxYxZ"
    CheckError error;
    std::string failure;         // the CPU reference threw on the GPU's inputs
    bool ok = true;
};

struct OutputCheck {
    std::string name;
    CheckError error;
    bool ok = true;
};

struct CheckDevice {
    std::string name, type, vulkan, driver;
    std::vector<std::pair<std::string, std::string>> limits;  // those that choose shader variants
};

struct CheckOptions {
    std::string model;    // weight file
    std::string tactile;  // tactile image
    std::string object;   // mesh (.glb/.gltf) or PLY point cloud
};

struct CheckResult {
    bool ok = false;
    CheckDevice device;
    std::string model_name;
    CheckTolerance node_tolerance{1e-4, 1e-4}, end_to_end_tolerance{2e-3, 2e-3};
    std::vector<NodeCheck> nodes;       // schedule order; each CPU node ran on the GPU's inputs
    std::vector<OutputCheck> outputs;   // the model's outputs against a full CPU run
    int first_failure = -1;             // index into nodes, -1 if none
    double gpu_ms = 0, cpu_ms = 0, wall_ms = 0;
};

// Runs the model once on the context's device (every intermediate kept) and
// compares every node with its CPU reference fed the GPU's own inputs, and the
// outputs with a full CPU reference run. Bad files throw Error; a mismatch
// does not throw (ok = false).
CheckResult check(Context& context, const CheckOptions& options);

struct OpCheck {
    std::string op, variant;
    std::vector<std::string> dispatches;
    CheckError error;
    CheckTolerance tolerance;
    std::string failure;  // recording or the reference threw
    bool ok = true;
    double ms = 0;
};

struct OpsCheckResult {
    bool ok = false;
    CheckDevice device;
    std::vector<OpCheck> cases;
    std::vector<std::string> uncovered_ops;  // registered ops with no self-test case (a failure)
    double wall_ms = 0;
};

// The built-in self-test: every registered op on the device against its CPU
// reference, at odd shapes and on each variant (texel / storage-buffer paths,
// the tile shapes this device's limits choose). filter: only ops whose name
// contains it. progress(i, n, case) after each case, when given.
OpsCheckResult check_ops(Context& context, const std::string& filter = "",
                         const std::function<void(size_t, size_t, const OpCheck&)>& progress = {});

// ---- Checking the multi-touch filter (`vtloc check --tracker`) ---------------

struct TrackerCheckOptions {
    std::string touches;         // a touches file (vtloc sequence's format); its motions drive the check
    std::string object;          // mesh or cloud; empty: the touches file's "object"
    int64_t hypotheses = 120000; // as TrackerOptions::hypotheses (the tables' sizes pick shader paths)
    double object_units = 1;     // as TrackerOptions::object_units
    // Then back over the touches in reverse (each motion inverted: poses the tour pressed), so
    // a tour no longer than the window (8) also reaches the steady state, the belief before
    // the window entering as a prior.
    bool there_and_back = true;
    // Each touch also carries a log term over the hypotheses (seeded: the same every run), as
    // render-and-compare's or the network's would: the step then reads a field per touch in
    // the window, not only the prior's, through the evidence's other path (segments of terms
    // each ending at a field, looked up at the moved pose's nearest hypothesis).
    bool touch_terms = false;
    // Instead, each touch's own frame (the touches file's "tactile") read into its gel's shape
    // (the reader's graph checked node by node on it, and the shape read against the CPU
    // reference run's) and scored against the object's codebook as render-and-compare's term, on
    // the device and by the CPU reference scorer (compared per frame), the device's term then
    // given to both trackers. Both score against the maps the tracker would (codebook_cache's, or
    // rendered on the device), checked against the CPU reference's render in `codebook`.
    bool shapes = false;
    // With shapes, how the frames are read (as vtloc sequence --render-compare reads them): the
    // reader for frames vtloc synth rendered (GelShapeOptions::rendered_frames(): the solve from a
    // coarse start, its pooling and prolongation nodes checked too), a calibration file (empty:
    // the shipped one) and the sensor's empty frame (empty: the calibration's).
    bool rendered_frames = false;
    std::string calibration, background;
    // With shapes: TrackerOptions::codebook_cache (a deployed cache checked too; written from the
    // device's render where missing, as a tracker would, and removed again if that render fails)
    // and how many of its maps the CPU reference re-renders, spread over them (0: all; ~1 s a 3,333).
    // Without shapes these five options must keep their defaults.
    std::string codebook_cache;
    int64_t codebook_samples = 0;
};

// The maps render-and-compare scores against, every sample's (or codebook_samples spread over
// them) re-rendered by the CPU reference.
struct CodebookCheck {
    int64_t samples = 0;         // the codebook's
    int64_t checked = 0;         // of them compared
    CheckError heights;
    bool ok = true;
};

struct ShapeTermCheck {
    std::string frame;           // the frame's path
    // The gel's shape read from it: the reader's graph node by node (each CPU node fed the
    // device's inputs; node_tolerance) and its outputs against a full CPU run (end_to_end_tolerance).
    std::vector<NodeCheck> shape_nodes;
    std::vector<OutputCheck> shape_outputs;
    int first_failure = -1;      // index into shape_nodes, -1 if none
    // The shape the term scores (the reader's, from its own executor) against the CPU reference
    // run's: the depth in mm (end_to_end_tolerance) and the contact (every pixel alike).
    CheckError depth;
    int64_t mask_pixels_differ = 0;
    CheckError term;             // the device's term against the CPU reference scorer's
    bool ok = true;              // the shape's nodes and outputs, the read shape, and the term
};

struct TouchCheck {
    int touch = 0;               // 1-based
    CheckError belief;           // the GPU tracker's belief against the CPU reference tracker's
    double contact_mm = 0;       // their estimates' contacts apart (reported; the host refines both)
    bool ok = true;
};

struct TrackerCheckResult {
    bool ok = false;
    CheckDevice device;
    std::string object;
    int64_t hypotheses = 0;      // as built (samples x spins)
    // The belief: |gpu - cpu| <= abs * (the reference's peak) + rel * |cpu| (the GPU's exp and log
    // are not correctly rounded and its sums run in another order: a hypothesis's log evidence
    // may differ by ~2e-3 over a window's terms).
    CheckTolerance belief_tolerance{1e-6, 5e-3};
    CheckTolerance node_tolerance{1e-4, 1e-4}, end_to_end_tolerance{2e-3, 2e-3};
    // Render-and-compare's term (shapes): |gpu - cpu| <= abs + rel*|cpu|, fp32's tolerance (the
    // scoring shader is `precise`, no contraction: lavapipe gives the reference's bits).
    CheckTolerance term_tolerance{1e-4, 1e-4};
    std::vector<ShapeTermCheck> shape_terms;  // with shapes: one per frame of the file
    int first_shape_failure = -1;             // the first frame whose gel shape node failed, -1 if none
    // The codebook's heights must match exactly: each is the least of identical fp32 values (the
    // render shader is `precise`, and Vulkan rounds +, -, * correctly), on any device.
    CheckTolerance height_tolerance{0, 0};
    CodebookCheck codebook;      // with shapes
    std::vector<TouchCheck> touches;   // both trackers walk the whole tour
    std::vector<NodeCheck> nodes;      // the last touch's step, each node's CPU reference on the GPU's inputs
    std::vector<OutputCheck> outputs;  // that step's outputs against a full CPU run
    int first_failure = -1;            // index into nodes, -1 if none
    double gpu_ms = 0, cpu_ms = 0, wall_ms = 0;
};

// Walks the touches file's tour on a GPU tracker and on its CPU reference twin (the same
// surface), comparing the beliefs after every touch, then checks the last touch's step
// graph node by node. Bad files throw Error; a mismatch does not throw (ok = false).
TrackerCheckResult check_tracker(Context& context, const TrackerCheckOptions& options);

}  // namespace vtloc::api
