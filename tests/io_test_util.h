#pragma once
// Helpers for the [io] tests: write small files byte by byte (so the readers
// are checked against files they did not write), and build glTF/GLB meshes.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/error.h"
#include "tests/harness.h"

namespace vtloc::test {

inline std::string write_temp(const std::string& name, const std::string& bytes) {
    std::string path = temp_path(name);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size()));
    return path;
}

template <class T>
void append_le(std::string& s, T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));  // the test hosts are little-endian
    s.append(b, sizeof(T));
}

// Runs f, requires a vtloc::Error whose message contains every fragment.
template <class F>
void require_error(F&& f, std::initializer_list<std::string> fragments) {
    try {
        f();
    } catch (const vtloc::Error& e) {
        std::string msg = e.what();
        INFO("message: " << msg);
        CHECK(msg.find('\n') == std::string::npos);  // one line
        for (auto& frag : fragments) CHECK(msg.find(frag) != std::string::npos);
        return;
    }
    FAIL("no vtloc::Error thrown");
}

// A glTF document with one buffer, built accessor by accessor.
struct GltfBuilder {
    nlohmann::json doc = {{"asset", {{"version", "2.0"}}},
                          {"bufferViews", nlohmann::json::array()},
                          {"accessors", nlohmann::json::array()},
                          {"meshes", nlohmann::json::array()},
                          {"nodes", nlohmann::json::array()}};
    std::string bin;

    int accessor(const void* data, size_t bytes, size_t count, int component, const char* type) {
        while (bin.size() % 4) bin.push_back('\0');
        doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}});
        bin.append(static_cast<const char*>(data), bytes);
        doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1},
                                    {"componentType", component},
                                    {"count", count},
                                    {"type", type}});
        return int(doc["accessors"].size()) - 1;
    }
    int vec3(const std::vector<float>& v) { return accessor(v.data(), v.size() * 4, v.size() / 3, 5126, "VEC3"); }
    int u16(const std::vector<uint16_t>& v) { return accessor(v.data(), v.size() * 2, v.size(), 5123, "SCALAR"); }
    int u32(const std::vector<uint32_t>& v) { return accessor(v.data(), v.size() * 4, v.size(), 5125, "SCALAR"); }

    // A primitive (indices < 0: none; normals < 0: none) in a new mesh; returns the mesh index.
    int mesh(int positions, int indices = -1, int normals = -1, int mode = 4) {
        nlohmann::json prim = {{"attributes", {{"POSITION", positions}}}, {"mode", mode}};
        if (normals >= 0) prim["attributes"]["NORMAL"] = normals;
        if (indices >= 0) prim["indices"] = indices;
        doc["meshes"].push_back({{"primitives", nlohmann::json::array({prim})}});
        return int(doc["meshes"].size()) - 1;
    }
    // A node holding a mesh, with optional extra fields (translation, rotation, scale, matrix, children).
    int node(int mesh, nlohmann::json extra = nlohmann::json::object()) {
        extra["mesh"] = mesh;
        doc["nodes"].push_back(extra);
        return int(doc["nodes"].size()) - 1;
    }
    void scene(std::vector<int> roots) {
        doc["scenes"] = nlohmann::json::array({{{"nodes", roots}}});
        doc["scene"] = 0;
    }

    std::string glb() {
        while (bin.size() % 4) bin.push_back('\0');
        doc["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}}});
        std::string js = doc.dump();
        while (js.size() % 4) js.push_back(' ');
        std::string out = "glTF";
        append_le<uint32_t>(out, 2);
        append_le<uint32_t>(out, uint32_t(12 + 8 + js.size() + 8 + bin.size()));
        append_le<uint32_t>(out, uint32_t(js.size()));
        out += "JSON" + js;
        append_le<uint32_t>(out, uint32_t(bin.size()));
        out.append("BIN\0", 4);
        return out + bin;
    }
    // .gltf text with the buffer in a separate file next to it.
    std::string write_gltf(const std::string& name) {
        std::string bin_path = write_temp(name + ".bin", bin);
        doc["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}, {"uri", name + ".bin"}}});
        (void)bin_path;
        return write_temp(name, doc.dump(1));
    }
};

// The 8 corners of an axis-aligned box [-hx, hx] x [-hy, hy] x [-hz, hz] and its
// 12 triangles, counter-clockwise seen from outside.
inline std::vector<float> box_corners(float hx, float hy, float hz) {
    std::vector<float> v;
    for (int i = 0; i < 8; ++i) v.insert(v.end(), {(i & 1) ? hx : -hx, (i & 2) ? hy : -hy, (i & 4) ? hz : -hz});
    return v;
}
inline std::vector<uint16_t> box_triangles() {
    return {0, 2, 3, 0, 3, 1,  4, 5, 7, 4, 7, 6,  0, 1, 5, 0, 5, 4,
            2, 6, 7, 2, 7, 3,  0, 4, 6, 0, 6, 2,  1, 3, 7, 1, 7, 5};
}

}  // namespace vtloc::test
