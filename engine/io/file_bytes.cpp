#include "engine/io/file_bytes.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "base/error.h"

namespace vtloc::io {

void fail(const std::string& path, const std::string& problem) { throw Error(path + ": " + problem); }

std::vector<uint8_t> read_file_bytes(const std::string& path) {
    std::error_code ec;
    auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status)) fail(path, "no such file");
    if (std::filesystem::is_directory(status)) fail(path, "is a directory, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot be opened (") + std::strerror(errno) + ")");
    in.seekg(0, std::ios::end);
    std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size < 0) fail(path, "cannot be read (not a regular file?)");
    std::vector<uint8_t> bytes(static_cast<size_t>(size));
    in.read(reinterpret_cast<char*>(bytes.data()), size);
    if (in.gcount() != size) fail(path, "read error");
    return bytes;
}

void write_file_bytes(const std::string& path, const void* data, size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) fail(path, std::string("cannot be written (") + std::strerror(errno) + ")");
    out.write(static_cast<const char*>(data), std::streamsize(size));
    out.close();
    if (!out) fail(path, "write error (disk full?)");
}

std::string extension_of(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    if (!ext.empty()) ext.erase(0, 1);
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

}  // namespace vtloc::io
