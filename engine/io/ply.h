#pragma once
// PLY files: the vertex element of ascii, binary_little_endian and
// binary_big_endian files (the formats weights_tools/ply.py reads), and a
// writer for point clouds with optional per-point probability and colour.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/tensor.h"

namespace vtloc::io {

// The scalar properties of a PLY file's vertex element, each value widened to
// double whatever its stored type (char .. double). List properties and
// other elements (faces, ...) are skipped.
struct PlyVertices {
    int64_t count = 0;
    std::vector<std::string> names;  // in file order
    std::vector<double> values;      // count x names.size(), row-major
    std::vector<std::string> elements;  // every element's name, in file order ("vertex", "face", ...)

    int column(const std::string& name) const;  // -1 when absent
};

// Throws vtloc::Error("<path>: ...") for a missing file, a file that is not a
// PLY, a malformed header (naming its line), no vertex element, a value that
// is not a number, or data that ends before the header's counts do.
PlyVertices read_ply_vertices(const std::string& path);

// N x names.size() float tensor of the named columns; throws naming the first
// property the file lacks.
HostTensor ply_columns(const PlyVertices& v, const std::vector<std::string>& names, const std::string& path);

enum class PlyFormat { Ascii, BinaryLittleEndian };

struct PlyWriteOptions {
    PlyFormat format = PlyFormat::BinaryLittleEndian;
    std::vector<float> contact_prob;  // empty, or one per point: `property float contact_prob`
    std::vector<uint8_t> rgb;         // empty, or three per point: `property uchar red/green/blue`
    std::vector<std::string> comments;  // one `comment` header line each
};

// points: N x 3 (x y z) or N x 6 (x y z nx ny nz). Ascii values are written
// in shortest round-trip form, so both formats read back bit for bit.
void write_ply(const std::string& path, const HostTensor& points, const PlyWriteOptions& options = {});

}  // namespace vtloc::io
