#pragma once
// The PLY header, read once for both PLY readers (point clouds: ply.cpp; meshes:
// mesh_ply_faces.cpp): its encoding, elements and properties, where the data starts,
// and one binary value widened to double. Internal to vtloc_io.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vtloc::io::ply {

enum class Type { I8, U8, I16, U16, I32, U32, F32, F64 };
size_t type_size(Type t);

struct Prop {
    std::string name;
    Type type = Type::F32;  // a list's item type
    bool list = false;
    Type count_type = Type::U8;
};

struct Elem {
    std::string name;
    int64_t count = 0;
    std::vector<Prop> props;
};

enum class Encoding { Ascii, Little, Big };

struct Header {
    Encoding encoding = Encoding::Ascii;
    std::vector<Elem> elems;
    size_t data_start = 0;  // the first byte after the end_header line
    int64_t lines = 0;      // the header's lines, end_header's included
};

// Throws vtloc::Error("<path>: ...") for a file that does not start with a 'ply' line, a
// header line it cannot read (naming the line and why), no end_header or no format line.
Header parse_header(const std::vector<uint8_t>& bytes, const std::string& path);

// The value of type t at p (type_size(t) bytes), in the file's byte order.
double read_binary(const uint8_t* p, Type t, bool big_endian);

}  // namespace vtloc::io::ply
