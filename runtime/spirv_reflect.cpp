#include "runtime/spirv_reflect.h"

#include <algorithm>
#include <map>
#include <set>

#include "base/error.h"

namespace vtloc::rt {

namespace {

// SPIR-V opcodes, decorations and storage classes used here (SPIR-V spec, section 3).
enum : uint32_t {
    OpCapability = 17, OpTypeInt = 21, OpTypeFloat = 22, OpTypeVector = 23, OpTypeMatrix = 24, OpTypeImage = 25,
    OpTypeSampledImage = 27, OpTypeArray = 28, OpTypeStruct = 30, OpTypePointer = 32,
    OpConstant = 43, OpVariable = 59, OpDecorate = 71, OpMemberDecorate = 72,
};
enum : uint32_t { DecBlock = 2, DecArrayStride = 6, DecBinding = 33, DecDescriptorSet = 34, DecOffset = 35 };
enum : uint32_t { ScUniformConstant = 0, ScUniform = 2, ScPushConstant = 9, ScStorageBuffer = 12 };
constexpr uint32_t kMagic = 0x07230203, kDimBuffer = 5;
// Capabilities GroupNonUniform (61) .. GroupNonUniformQuad (68): subgroup operations.
constexpr uint32_t kCapSubgroupFirst = 61, kCapSubgroupLast = 68;

struct Type {
    uint32_t op = 0;
    std::vector<uint32_t> args;  // operands after the result id
};

struct Module {
    std::map<uint32_t, Type> types;
    std::map<uint32_t, uint32_t> constants;                  // id -> value (32-bit)
    std::map<uint32_t, std::pair<uint32_t, uint32_t>> vars;  // id -> (pointer type, storage class)
    std::map<uint32_t, uint32_t> binding, set, array_stride;
    std::set<uint32_t> block;  // struct types decorated Block (uniform blocks in the Uniform class)
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> member_offset;
    bool subgroup_ops = false;
};

Module parse(std::span<const uint32_t> w, const std::string& shader) {
    if (w.size() < 5 || w[0] != kMagic) throw Error("shader '" + shader + "': not a SPIR-V module");
    Module m;
    for (size_t i = 5; i < w.size();) {
        const uint32_t count = w[i] >> 16, op = w[i] & 0xffff;
        if (count == 0 || i + count > w.size()) throw Error("shader '" + shader + "': truncated SPIR-V");
        const uint32_t* a = &w[i + 1];
        const uint32_t n = count - 1;
        switch (op) {
        case OpCapability:
            if (n >= 1 && a[0] >= kCapSubgroupFirst && a[0] <= kCapSubgroupLast) m.subgroup_ops = true;
            break;
        case OpTypeInt: case OpTypeFloat: case OpTypeVector: case OpTypeMatrix: case OpTypeImage:
        case OpTypeSampledImage: case OpTypeArray: case OpTypeStruct: case OpTypePointer:
            if (n >= 1) m.types[a[0]] = Type{op, std::vector<uint32_t>(a + 1, a + n)};
            break;
        case OpConstant:
            if (n >= 3) m.constants[a[1]] = a[2];
            break;
        case OpVariable:
            if (n >= 3) m.vars[a[1]] = {a[0], a[2]};
            break;
        case OpDecorate:
            if (n >= 3 && a[1] == DecBinding) m.binding[a[0]] = a[2];
            if (n >= 3 && a[1] == DecDescriptorSet) m.set[a[0]] = a[2];
            if (n >= 3 && a[1] == DecArrayStride) m.array_stride[a[0]] = a[2];
            if (n >= 2 && a[1] == DecBlock) m.block.insert(a[0]);
            break;
        case OpMemberDecorate:
            if (n >= 4 && a[2] == DecOffset) m.member_offset[{a[0], a[1]}] = a[3];
            break;
        default:
            break;
        }
        i += count;
    }
    return m;
}

uint32_t type_bytes(const Module& m, uint32_t id, const std::string& shader, int depth = 0) {
    auto it = m.types.find(id);
    if (it == m.types.end() || depth > 16) throw Error("shader '" + shader + "': push constants of an unknown type");
    const Type& t = it->second;
    switch (t.op) {
    case OpTypeInt: case OpTypeFloat:
        return t.args.at(0) / 8;
    case OpTypeVector: case OpTypeMatrix:
        return t.args.at(1) * type_bytes(m, t.args.at(0), shader, depth + 1);
    case OpTypeArray: {
        const uint32_t len = m.constants.at(t.args.at(1));
        auto s = m.array_stride.find(id);
        return len * (s != m.array_stride.end() ? s->second : type_bytes(m, t.args.at(0), shader, depth + 1));
    }
    case OpTypeStruct: {
        uint32_t end = 0;
        for (uint32_t k = 0; k < t.args.size(); ++k) {
            auto off = m.member_offset.find({id, k});
            const uint32_t at = off != m.member_offset.end() ? off->second : end;
            end = std::max(end, at + type_bytes(m, t.args[k], shader, depth + 1));
        }
        return end;
    }
    default:
        throw Error("shader '" + shader + "': push constants of an unsupported type");
    }
}

// What a set-0 variable is, from its pointee type and storage class.
BindingKind kind_of(const Module& m, uint32_t pointee, uint32_t storage) {
    // Storage buffers are Uniform + BufferBlock (SPIR-V <= 1.3) or StorageBuffer;
    // uniform buffers are Uniform + Block.
    if (storage == ScStorageBuffer) return BindingKind::StorageBuffer;
    if (storage == ScUniform) return m.block.count(pointee) ? BindingKind::UniformBuffer : BindingKind::StorageBuffer;
    if (storage != ScUniformConstant) return BindingKind::Other;
    auto t = m.types.find(pointee);
    if (t != m.types.end() && t->second.op == OpTypeSampledImage) t = m.types.find(t->second.args.at(0));
    if (t != m.types.end() && t->second.op == OpTypeImage && t->second.args.size() >= 2 && t->second.args[1] == kDimBuffer)
        return BindingKind::TexelBuffer;
    return BindingKind::Other;
}

}  // namespace

ShaderInterface reflect_spirv(std::span<const uint32_t> words, const std::string& shader) {
    const Module m = parse(words, shader);
    ShaderInterface out;
    out.subgroup_ops = m.subgroup_ops;
    for (const auto& [id, var] : m.vars) {
        const auto ptr = m.types.find(var.first);
        if (ptr == m.types.end() || ptr->second.op != OpTypePointer || ptr->second.args.size() < 2) continue;
        const uint32_t storage = var.second, pointee = ptr->second.args[1];
        if (storage == ScPushConstant) {
            out.push_bytes = type_bytes(m, pointee, shader);
            continue;
        }
        auto b = m.binding.find(id);
        if (b == m.binding.end()) continue;
        auto s = m.set.find(id);
        if (s != m.set.end() && s->second != 0)
            throw Error("shader '" + shader + "' uses descriptor set " + std::to_string(s->second) + "; the engine binds set 0 only");
        if (out.bindings.size() <= b->second) out.bindings.resize(b->second + 1, BindingKind::Other);
        out.bindings[b->second] = kind_of(m, pointee, storage);
    }
    return out;
}

}  // namespace vtloc::rt
