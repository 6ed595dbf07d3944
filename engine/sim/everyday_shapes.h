#pragma once
// Everyday objects like the paper's benchmark (issue #44): kitchenware,
// cutlery, tools and small household things at their real size in mm, with
// parts at the GelSight pad's scale (a 15 x 20 mm window): a mug's handle, a
// fork's tines, a key's bitting, a bottle cap's ridges. They join the
// procedural shapes' registry (shapes.h: make_shape, shape_names,
// shape_scale_mm) and shape_symmetry (symmetry.h) under their plain names.
#include <vector>

#include "engine/io/mesh.h"
#include "engine/sim/symmetry.h"

namespace vtloc::sim {

struct EverydayShape {
    const char* name;
    double scale_mm;             // largest bounding-box dimension as built
    io::TriangleMesh (*build)();
    Symmetry symmetry;           // in the object's own frame (none for most)
};

// In registry order. Each mesh is closed and wound outward; an object of
// several parts (a mug's body and handle) lists each part closed on its own,
// overlapping where they join.
const std::vector<EverydayShape>& everyday_shapes();

}  // namespace vtloc::sim
