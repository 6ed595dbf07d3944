#pragma once
// Procedural training objects: simple solids (uniform by SPEC section 5's rule)
// and shapes with fine teeth, ridges and threads (non-uniform), as closed or
// triangle meshes wound outward. Units are mm at each shape's natural size.
// The non-uniform shapes carry 1-3 mm teeth, ridges and threads at that size:
// the dataset builder, which rescales each object's largest dimension into
// 50-250 mm, should keep them near shape_scale_mm so the features stay at a
// realistic scale for the GelSight pad (the rule itself is scale-free). The
// registry also holds 25 everyday objects (mug, spoon, key, ...: everyday_shapes.h).
#include <string>
#include <vector>

#include "engine/io/mesh.h"

namespace vtloc::sim {

// Names accepted by make_shape ("box", "cylinder", ..., "comb", "gear", ...).
std::vector<std::string> shape_names();

// Throws vtloc::Error for an unknown name (listing the known ones).
io::TriangleMesh make_shape(const std::string& name);

// The largest bounding-box dimension (mm) the shape was designed for, which is
// also its size as built: the builder's recommended scale. Throws as above.
double shape_scale_mm(const std::string& name);

}  // namespace vtloc::sim
