#pragma once
// Whole-file reads and the "<path>: <problem>" errors that every loader in
// engine/io shares, so that a user always learns which file was wrong.
#include <cstdint>
#include <string>

#include "base/atomic_write.h"
#include <vector>

namespace vtloc::io {

// Throws vtloc::Error("<path>: <problem>").
[[noreturn]] void fail(const std::string& path, const std::string& problem);

// The file's bytes; a missing file, a directory or a read error each throw
// with their own message.
std::vector<uint8_t> read_file_bytes(const std::string& path);

// Writes bytes to path (replacing it); throws naming the path when it cannot.
void write_file_bytes(const std::string& path, const void* data, size_t size);
using vtloc::write_file_atomic;  // base/atomic_write.h: temporary name, then rename

// Lower-case extension without the dot ("PLY" -> "ply", none -> "").
std::string extension_of(const std::string& path);

}  // namespace vtloc::io
