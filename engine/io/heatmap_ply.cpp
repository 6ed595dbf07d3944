#include "engine/io/heatmap_ply.h"

#include "base/error.h"
#include "engine/io/colormap.h"

namespace vtloc::io {

void write_heatmap_ply(const std::string& path, const HostTensor& cloud, std::span<const float> heat,
                       PlyFormat format) {
    if (cloud.shape.size() != 2 || size_t(cloud.shape[0]) != heat.size())
        throw Error("write_heatmap_ply(" + path + "): " + std::to_string(heat.size()) + " heat values for a cloud of " +
                    shape_str(cloud.shape));
    PlyWriteOptions o;
    o.format = format;
    o.comments = {"VTLoc contact heat-map: contact_prob in [0, 1], colour from contact_prob"};
    o.contact_prob.assign(heat.begin(), heat.end());
    o.rgb.reserve(heat.size() * 3);
    for (float h : heat) {
        auto c = heat_color(h);
        o.rgb.insert(o.rgb.end(), c.begin(), c.end());
    }
    write_ply(path, cloud, o);
}

}  // namespace vtloc::io
