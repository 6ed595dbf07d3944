#pragma once
// Points as text (.xyz, .csv, .txt; candidates in any non-PLY file), as
// weights_tools/inputs.py reads them: one point per line, values separated by
// commas and/or white space, '#' starts a comment. One header line (the first
// non-comment line, when it is not all numbers, e.g. "x,y,z") is skipped.
#include <string>

#include "engine/tensor.h"

namespace vtloc::io {

// N x 3 (x y z: the first three columns), or N x 6 when keep_normals and rows
// have at least six values (x y z nx ny nz). Throws vtloc::Error naming the
// file and line for a missing file, a value that is not a number, a row with
// fewer than 3 values or a different count than the first, a non-finite value,
// or no points at all ("no <what> in the file").
HostTensor load_point_text(const std::string& path, const std::string& what, bool keep_normals);

}  // namespace vtloc::io
