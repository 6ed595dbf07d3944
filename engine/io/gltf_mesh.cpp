// glTF loading through tinygltf. Its implementation is compiled here, in the
// only file that includes tiny_gltf.h, with image decoding and writing turned
// off: we need geometry only, so neither stb nor textures are involved, and
// the macros cannot disagree between translation units.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "engine/io/file_bytes.h"
#include "engine/io/mesh.h"

namespace vtloc::io {

namespace {

// Images are skipped, not decoded (embedded textures would otherwise fail to load).
bool ignore_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                  void*) {
    return true;
}

struct Loader {
    const std::string& path;
    const tinygltf::Model& model;
    TriangleMesh out;
    bool any_normals = false;
    size_t skipped_primitives = 0;

    // A typed, bounds-checked view of an accessor's elements.
    struct View {
        const uint8_t* base = nullptr;
        size_t stride = 0, count = 0;
        int component = 0;
    };

    View view(int index, const std::string& where, const char* what) const {
        auto bad = [&](const std::string& why) { fail(path, where + ": " + what + " accessor " + why); };
        if (index < 0 || size_t(index) >= model.accessors.size()) bad("index out of range");
        const auto& a = model.accessors[size_t(index)];
        if (a.sparse.isSparse) bad("is sparse (not supported)");
        if (a.bufferView < 0 || size_t(a.bufferView) >= model.bufferViews.size())
            bad("has no buffer view (compressed meshes are not supported)");
        const auto& bv = model.bufferViews[size_t(a.bufferView)];
        if (bv.buffer < 0 || size_t(bv.buffer) >= model.buffers.size()) bad("refers to a missing buffer");
        const auto& buf = model.buffers[size_t(bv.buffer)].data;
        int stride = a.ByteStride(bv);
        int elem = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType)) *
                   tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (stride <= 0 || elem <= 0) bad("has an invalid type or stride");
        size_t begin = bv.byteOffset + a.byteOffset;
        size_t need = a.count ? size_t(stride) * (a.count - 1) + size_t(elem) : 0;
        if (begin + need > bv.byteOffset + bv.byteLength || bv.byteOffset + bv.byteLength > buf.size())
            bad("reaches past the end of its buffer");
        return {buf.data() + begin, size_t(stride), a.count, a.componentType};
    }

    // VEC3 of FLOAT, read as double.
    std::vector<glm::dvec3> vec3s(int index, const std::string& where, const char* what) const {
        View v = view(index, where, what);  // validates index first
        const auto& a = model.accessors[size_t(index)];
        if (a.type != TINYGLTF_TYPE_VEC3 || a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.normalized)
            fail(path, where + ": " + what + " must be VEC3 of FLOAT (quantized meshes are not supported)");
        std::vector<glm::dvec3> r(v.count);
        for (size_t i = 0; i < v.count; ++i) {
            float f[3];
            std::memcpy(f, v.base + i * v.stride, sizeof f);
            r[i] = glm::dvec3(f[0], f[1], f[2]);
        }
        return r;
    }

    std::vector<uint32_t> indices(int index, const std::string& where) const {
        View v = view(index, where, "indices");
        const auto& a = model.accessors[size_t(index)];
        if (a.type != TINYGLTF_TYPE_SCALAR) fail(path, where + ": indices must be SCALAR");
        std::vector<uint32_t> r(v.count);
        for (size_t i = 0; i < v.count; ++i) {
            const uint8_t* p = v.base + i * v.stride;
            switch (v.component) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: r[i] = *p; break;
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t s; std::memcpy(&s, p, 2); r[i] = s; break; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: std::memcpy(&r[i], p, 4); break;
                default: fail(path, where + ": indices must be unsigned byte, short or int");
            }
        }
        return r;
    }

    void add_primitive(const tinygltf::Primitive& prim, const glm::dmat4& world, const std::string& where) {
        if (prim.mode != -1 && prim.mode != TINYGLTF_MODE_TRIANGLES) {
            ++skipped_primitives;
            return;
        }
        auto pos_it = prim.attributes.find("POSITION");
        if (pos_it == prim.attributes.end()) fail(path, where + ": no POSITION attribute");
        std::vector<glm::dvec3> pos = vec3s(pos_it->second, where, "POSITION");
        const size_t base = out.vertex_count();
        for (size_t i = 0; i < pos.size(); ++i) {
            glm::dvec3 p = glm::dvec3(world * glm::dvec4(pos[i], 1.0));
            if (!std::isfinite(pos[i].x) || !std::isfinite(pos[i].y) || !std::isfinite(pos[i].z) ||
                !std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                fail(path, where + ": vertex " + std::to_string(i) + " has a non-finite coordinate");
            out.positions.insert(out.positions.end(), {float(p.x), float(p.y), float(p.z)});
        }
        glm::dmat3 lin(world);
        double det = glm::determinant(lin);
        auto nrm_it = prim.attributes.find("NORMAL");
        // A singular transform flattens the primitive (zero area): its normals cannot be mapped, nor are they needed.
        bool has_normals = nrm_it != prim.attributes.end() && std::abs(det) > 1e-300;
        if (has_normals && !any_normals) {
            out.normals.assign(base * 3, 0.0f);
            any_normals = true;
        }
        if (has_normals) {
            std::vector<glm::dvec3> nrm = vec3s(nrm_it->second, where, "NORMAL");
            if (nrm.size() != pos.size()) fail(path, where + ": NORMAL and POSITION counts differ");
            glm::dmat3 to_world = glm::transpose(glm::inverse(lin));
            for (size_t i = 0; i < nrm.size(); ++i) {
                glm::dvec3 n = to_world * nrm[i];
                double len = glm::length(n);
                if (!std::isfinite(len)) fail(path, where + ": normal of vertex " + std::to_string(i) + " is not finite");
                if (len < 1e-12) fail(path, where + ": normal of vertex " + std::to_string(i) + " is zero");
                n /= len;
                out.normals.insert(out.normals.end(), {float(n.x), float(n.y), float(n.z)});
            }
        } else if (any_normals) {
            out.normals.resize(out.positions.size(), 0.0f);
        }
        std::vector<uint32_t> idx;
        if (prim.indices >= 0) {
            idx = indices(prim.indices, where);
            for (size_t i = 0; i < idx.size(); ++i)
                if (idx[i] >= pos.size())
                    fail(path, where + ": index " + std::to_string(i) + " refers to vertex " + std::to_string(idx[i]) +
                                   " of " + std::to_string(pos.size()));
        } else {
            idx.resize(pos.size());
            for (size_t i = 0; i < idx.size(); ++i) idx[i] = uint32_t(i);
        }
        // A mirroring transform turns counter-clockwise into clockwise (glTF spec 3.7.4): swap to keep fronts.
        bool flip = det < 0;
        for (size_t t = 0; t + 2 < idx.size(); t += 3) {
            out.triangles.push_back(uint32_t(base + idx[t]));
            out.triangles.push_back(uint32_t(base + idx[t + (flip ? 2 : 1)]));
            out.triangles.push_back(uint32_t(base + idx[t + (flip ? 1 : 2)]));
        }
    }

    void add_mesh(int mesh_index, const glm::dmat4& world) {
        if (mesh_index < 0 || size_t(mesh_index) >= model.meshes.size()) fail(path, "node refers to a missing mesh");
        const auto& mesh = model.meshes[size_t(mesh_index)];
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            std::string where = "mesh " + std::to_string(mesh_index) + (mesh.name.empty() ? "" : " '" + mesh.name + "'") +
                                " primitive " + std::to_string(p);
            add_primitive(mesh.primitives[p], world, where);
        }
    }

    static glm::dmat4 local_transform(const tinygltf::Node& n) {
        if (n.matrix.size() == 16) return glm::make_mat4(n.matrix.data());  // column-major, as glm
        glm::dmat4 m(1.0);
        if (n.translation.size() == 3) m = glm::translate(m, glm::dvec3(n.translation[0], n.translation[1], n.translation[2]));
        if (n.rotation.size() == 4)  // glTF stores x, y, z, w; glm's constructor takes w first
            m *= glm::mat4_cast(glm::normalize(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2])));
        if (n.scale.size() == 3) m = glm::scale(m, glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
        return m;
    }

    void visit(int node, const glm::dmat4& parent, size_t depth) {
        if (node < 0 || size_t(node) >= model.nodes.size()) fail(path, "scene refers to a missing node");
        if (depth > model.nodes.size()) fail(path, "node hierarchy has a cycle");
        const auto& n = model.nodes[size_t(node)];
        glm::dmat4 world = parent * local_transform(n);
        if (n.mesh >= 0) add_mesh(n.mesh, world);
        for (int c : n.children) visit(c, world, depth + 1);
    }

    void run() {
        std::vector<int> roots;
        if (!model.scenes.empty()) {
            size_t s = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size()
                           ? size_t(model.defaultScene) : 0;
            roots = model.scenes[s].nodes;
        } else {
            // No scene: every node that is nobody's child.
            std::vector<bool> child(model.nodes.size(), false);
            for (auto& n : model.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < child.size()) child[size_t(c)] = true;
            for (size_t i = 0; i < child.size(); ++i)
                if (!child[i]) roots.push_back(int(i));
        }
        if (model.nodes.empty()) {
            for (size_t m = 0; m < model.meshes.size(); ++m) add_mesh(int(m), glm::dmat4(1.0));
        } else {
            for (int r : roots) visit(r, glm::dmat4(1.0), 0);
        }
        if (out.triangles.empty()) {
            if (model.meshes.empty()) fail(path, "glTF file holds no mesh");
            if (skipped_primitives)
                fail(path, "mesh has no triangles (" + std::to_string(skipped_primitives) +
                               " primitives of other modes skipped)");
            fail(path, "mesh has no triangles (no mesh in the scene, or empty primitives)");
        }
    }
};

}  // namespace

TriangleMesh load_gltf_mesh(const std::string& path) {
    std::vector<uint8_t> bytes = read_file_bytes(path);
    if (bytes.empty()) fail(path, "file is empty, not a glTF file");
    if (bytes.size() > 0xFFFFFFFFull) fail(path, "file too large for tinygltf (4 GiB)");
    tinygltf::TinyGLTF gltf;
    gltf.SetImageLoader(ignore_image, nullptr);
    tinygltf::Model model;
    std::string err, warn;
    std::string base_dir = std::filesystem::path(path).parent_path().string();
    bool ok = false;
    try {
        bool glb = bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
        if (glb)
            ok = gltf.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), unsigned(bytes.size()), base_dir);
        else
            ok = gltf.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                          unsigned(bytes.size()), base_dir);
    } catch (const std::exception& e) {
        err = e.what();
    }
    if (!ok) {
        // tinygltf's messages can span lines; ours stay on one.
        for (char& c : err)
            if (c == '\n' || c == '\r') c = ' ';
        while (!err.empty() && err.back() == ' ') err.pop_back();
        fail(path, "not a valid glTF file (" + (err.empty() ? std::string("tinygltf gave no reason") : err) + ")");
    }
    Loader loader{path, model, {}};
    loader.run();
    return std::move(loader.out);
}

}  // namespace vtloc::io
