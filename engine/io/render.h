#pragma once
// A PNG-ready picture of a heat-map: the object's points coloured by contact
// probability, seen from two sides, with the predicted (and true) contact
// marked, a colour bar and a caption. For people, not for measurements.
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/io/image.h"
#include "engine/tensor.h"

namespace vtloc::io {

struct RenderOptions {
    int width = 1280, height = 720;                    // at least 640 x 400
    std::optional<std::array<float, 3>> contact;       // predicted contact c^p, object units
    std::optional<std::array<float, 3>> ground_truth;  // true contact, object units
    std::array<float, 3> up = {0, 1, 0};               // object axis drawn upwards (glTF's +y)
    std::string caption;                               // one line above the views
    const RgbImage* tactile = nullptr;                 // shown in the side bar when given
};

// cloud: N x 6 (xyz, normal); heat: N values in [0, 1]. Two orthographic
// views share one scale: the left one looks at the predicted contact (from
// its surface normal, turned 20 degrees for depth), or without a contact a
// 3/4 view of the object's widest side; the right one is the opposite side.
// Points are shaded discs drawn back to front; a marker behind the surface is
// drawn faded. Throws vtloc::Error for mismatched sizes.
RgbImage render_heatmap(const HostTensor& cloud, std::span<const float> heat, const RenderOptions& options = {});

// Heat for display points, e.g. a denser sample of the same mesh, which reads
// far better than the model's 1024 points: each row of `points` (M x 3 or
// M x 6) takes the heat of its nearest point of `cloud` (N x 3 or N x 6;
// brute force, O(M N)). For pictures only: SPEC's heat-map is defined on P.
std::vector<float> nearest_heat(const HostTensor& cloud, std::span<const float> heat, const HostTensor& points);

}  // namespace vtloc::io
