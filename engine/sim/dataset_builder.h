#pragma once
// `vtloc synth`: meshes in, a `vtloc-synth/1` dataset (docs/dataset.md) out.
// Deterministic from the seed: each object draws from its own generator
// (seed, object index), so objects can be built in any order, in parallel,
// and an interrupted build resumes object by object.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace vtloc::sim {

struct ObjectSource {
    std::string source;               // "shape:<name>" or a mesh file path
    std::optional<double> scale_mm;   // largest bounding-box side; drawn when absent
    // "seen" / "unseen" pins the object's split; absent: the seeded stratified
    // split among the objects left unpinned (so a benchmark can grow without
    // moving an object a model was trained on into its unknown set).
    std::string split;
    // A mesh file's half turn about x, y or z of its frame through its bounding box's centre
    // (`half-turn:x`): its symmetry group (a procedural shape's is declared in symmetry.cpp);
    // 0: none. The builder checks it holds within symmetry_residual_mm's 0.2 mm.
    char half_turn = 0;
};

// One object per line: `<source> [scale_mm] [half-turn:x|y|z] [seen|unseen]`, `#` starts a
// comment. Relative mesh paths resolve against mesh_dir (default: the list's folder). Throws
// vtloc::Error naming the file and line.
std::vector<ObjectSource> read_object_list(const std::string& path, const std::string& mesh_dir = "");

struct BuildOptions {
    std::string out;
    uint64_t seed = 1;
    int contacts = 40;                // train + test contacts per object
    double test_fraction = 0.3;       // the 7:3 contact split
    int extra = 0;                    // extra training touches per object (>= 2 mm from every test contact)
    int extra_views = 1;              // renders per extra contact, each with its own spin, press, tilt and look
    int n_points = 1024;
    double max_tilt_deg = 5;          // tilt of the sensor axis, uniform in [0, max]
    double press_min_mm = 0.3, press_max_mm = 1.5;
    double min_separation_mm = 3;     // between any two train/test contacts of an object
    double unseen_fraction = 0.3;     // the 7:3 object split, stratified by subset
    bool randomize_train_look = true; // train/extra: background brightness, colour, blur, noise
    std::string calibration;          // "" = the shipped calibration
    std::string background;           // a user's empty sensor frame (PNG) replacing the calibration's
    std::optional<double> mm_per_px;  // a user's pixel size
    int threads = 0;                  // 0 = hardware concurrency
    // Also write each object's single-view cloud (partial_view.h: view.xyz,
    // view.json), for built and resumed objects alike; not part of the options
    // a resumed dataset must match, so --view can be added to a built dataset.
    bool view = false;
    // Also write each touch's gel indentation (the renderer's ground-truth
    // geometry) as touches/<id>.depth.png: 16-bit grey, micrometres.
    bool indentation = false;
    // Called after each object: (objects done, objects total, touches rendered so far).
    std::function<void(int, int, long)> progress;
};

struct BuildReport {
    int objects = 0, resumed = 0;
    long touches = 0, rejected = 0;   // rendered / rejected (unreachable, missed) contact draws
    double seconds = 0;
    std::vector<std::string> notes;   // objects that got fewer contacts than asked, ...
};

// Throws vtloc::Error for bad sources (naming the file), an output folder
// built with other options, or an object on which no contact is reachable.
BuildReport build_dataset(const std::vector<ObjectSource>& objects, const BuildOptions& options);

}  // namespace vtloc::sim
