#pragma once
// The on-disk dataset layout `vtloc-synth/1` (docs/dataset.md): what `vtloc
// synth` writes and `vtloc eval` reads. Plain JSON, CSV and PNG.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "base/atomic_write.h"
#include "engine/sim/symmetry.h"
#include "engine/tensor.h"

namespace vtloc::sim {

inline constexpr const char* kDatasetFormat = "vtloc-synth/1";

struct SensorInfo {
    int height = 120, width = 160;
    double mm_per_px = 0.1245;
    std::string calibration = "objectfolder_gelsight_calib";
};

struct TouchRecord {
    int id = 0;
    std::string split;             // "train", "test" or "extra"
    int order = -1;                // collection order; -1 for "extra"
    std::string image;             // relative to the object folder
    std::array<double, 3> contact{}, normal{};
    std::array<double, 9> R{};     // row-major; columns = sensor x, y, z
    std::array<double, 3> t{};     // sensor centre
    double press_mm = 0, spin_deg = 0, tilt_deg = 0;
    std::array<double, 3> motion{};   // sensor-centre translation from the previous touch (object frame)
    std::array<double, 9> rel_R{1, 0, 0, 0, 1, 0, 0, 0, 1};  // this pose in the previous pose's frame
    std::array<double, 3> rel_t{};
};

struct ObjectRecord {
    std::string name;
    std::string source;            // where the mesh came from
    std::string subset;            // "uniform" / "non-uniform"
    double dn_share = 0;
    std::string object_split;      // "seen" / "unseen"
    double scale_mm = 0, diameter_mm = 0;
    int n_points = 0;
    uint64_t sample_seed = 0;
    std::string folder;            // absolute or relative to the dataset root, as read
    HostTensor points;             // N x 6, mm
    std::vector<TouchRecord> touches;  // in id order
    Symmetry symmetry;             // its rigid symmetries (none unless declared: object.json "symmetry")
    bool has_mesh = false;         // mesh.ply present
    bool has_background = false;   // background.png present

    // Candidates S^c: the contacts of the "test" touches, in id order (K x 3).
    HostTensor candidates() const;
    std::vector<const TouchRecord*> touches_of(const std::string& split) const;
};

struct Dataset {
    std::string root;
    uint64_t seed = 0;
    SensorInfo sensor;
    int n_points = 0;
    std::vector<ObjectRecord> objects;
};

// Reads dataset.json and every object's object.json, points.csv and
// touches.csv (images are not opened). Throws vtloc::Error naming the file
// (and line) for a folder that is not a dataset, a wrong format string, a
// missing file or column, a malformed number, or inconsistent counts.
Dataset read_dataset(const std::string& root);

// Writers used by the builder: each writes `path + ".tmp"` and renames.
void write_object_json(const std::string& path, const ObjectRecord& o);
void write_points_csv(const std::string& path, const HostTensor& points);
void write_touches_csv(const std::string& path, const std::vector<TouchRecord>& touches);
void write_dataset_json(const std::string& path, const Dataset& d);

using vtloc::write_file_atomic;  // base/atomic_write.h

}  // namespace vtloc::sim
