#pragma once
// One object of a `vtloc synth` dataset (internal to the builder): its mesh,
// cloud, contacts, touches and files, built into objects/<name>.tmp and renamed
// into place, so an interrupted build never leaves a torn object behind.
#include <atomic>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "engine/sensor/calibration.h"
#include "engine/sim/dataset.h"
#include "engine/sim/dataset_builder.h"

namespace vtloc::sim {

// The sensor model lives in engine/sensor; the simulator names it as before.
using sensor::Calibration;
using sensor::default_calibration_path;
using sensor::load_calibration;

struct Job {
    int index = 0;
    ObjectSource src;
    std::string name;
};

struct Shared {
    const BuildOptions& opt;
    const Calibration& calib;
    std::vector<float> background;  // user's empty frame, stored order; empty = calibration's
    std::atomic<long> touches{0}, rejected{0};
    std::mutex mu;
    std::vector<std::string> notes;
};

// Deterministic from the dataset seed and job.index, whatever the thread.
ObjectRecord build_object(const Job& job, Shared& sh);

// What build_dataset needs of an object already built (a resumed run).
ObjectRecord read_built_object(const std::filesystem::path& dir);

}  // namespace vtloc::sim
