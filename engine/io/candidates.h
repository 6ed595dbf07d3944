#pragma once
// Candidate contact points S^c (SPEC section 1), object units.
#include <string>

#include "engine/tensor.h"

namespace vtloc::io {

// M x 3. A .ply file gives its vertices' x y z (other properties ignored).
// Any other file is text, as weights_tools/inputs.py reads it: one point per
// line, values separated by commas and/or white space, '#' starts a comment;
// columns after the third are ignored. One header line (the first non-comment
// line, when it is not all numbers, e.g. "x,y,z") is skipped. Throws
// vtloc::Error naming the file (and line) for a missing file, a value that is
// not a number, a row with fewer than 3 values or a different count than the
// first, a non-finite value, or no points at all.
HostTensor load_candidates(const std::string& path);

}  // namespace vtloc::io
