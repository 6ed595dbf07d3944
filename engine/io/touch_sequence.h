#pragma once
// The touches file of `vtloc sequence` and `vtloc demo` ("format":
// "vtloc-touches/2"): each touch's tactile frame and the robot's motion, either
// relative (this touch's sensor pose in the previous one's frame) or absolute
// flange poses with a flange-to-sensor tool. Every motion is checked (finite, a
// proper rotation) here, so a bad file fails naming the file and the touch
// before any work starts. Optional per-touch "contact" records the truth
// (examples; the demo prints its error against it).
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/rigid.h"

namespace vtloc::io {

struct SequenceTouch {
    std::string tactile;                          // resolved against the file's folder
    std::optional<Rigid> motion;                  // relative, from the previous touch
    std::optional<Rigid> flange;                  // absolute, robot frame
    std::optional<std::array<double, 3>> contact; // the truth, where the file records it
};

struct TouchSequence {
    std::vector<SequenceTouch> touches;
    bool flange = false;         // "motion": "flange"
    std::optional<Rigid> tool;   // flange to sensor
    std::string object;          // optional "object" path, resolved like the frames
    double object_diameter_mm = 0;  // optional, for ND in the demo
    std::string where;           // optional description

    // The relative motion into each touch (none for the first), from the
    // relative motions or from the flange poses and the tool (throws naming
    // `name` when flange poses have no tool).
    std::vector<std::optional<Rigid>> relative_motions(const std::string& name) const;
};

// `name` prefixes every error (the file's path); `base` resolves relative paths.
TouchSequence parse_touch_sequence(std::string_view json_text, const std::filesystem::path& base, const std::string& name);
TouchSequence read_touch_sequence(const std::string& path);

}  // namespace vtloc::io
