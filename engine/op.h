#pragma once
// What an op is: shape inference, a plain C++ reference (the test oracle) and
// a GPU recorder that dispatches its shader(s). Ops are listed in
// engine/ops/registry.cpp; adding one = a .comp, an engine/ops/<op>.cpp,
// a test and a registry line.
#include <string>
#include <string_view>
#include <vector>

#include "engine/graph.h"
#include "engine/tensor.h"
#include "runtime/memory.h"

namespace vtloc {
namespace rt {
class Context;
class Sequence;
struct DeviceInfo;
}  // namespace rt

struct GpuTensor {
    rt::BufferView view;
    Shape shape;
};

struct GpuOpArgs {
    rt::Context& ctx;
    rt::Sequence& seq;
    const std::vector<GpuTensor>& in;
    const std::vector<GpuTensor>& out;
    const Params& params;
    // OpDef::scratch_bytes of this node's bytes, for its own use within the node (the
    // executor shares one buffer among all nodes; barriers follow from the byte ranges).
    rt::BufferView scratch{};
};

struct OpDef {
    std::string_view name;
    // Throws vtloc::Error describing the mismatch (the graph adds the node's name).
    std::vector<TensorDesc> (*infer)(const std::vector<TensorDesc>& in, const Params& p);
    void (*cpu)(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out,
                const Params& p);
    void (*gpu)(const GpuOpArgs& a);
    // Bit i set: output i is a workspace whose contents are unspecified (the
    // GPU's scratch), so checks of a node's outputs skip it (engine/check/).
    uint32_t workspace_outputs = 0;
    // Every parameter the op reads: Graph::add refuses any other name, so a
    // misspelt one is an error, not a silent default (engine/ops/build.h
    // makes it a compile error for typed callers).
    std::vector<std::string_view> params;
    // Where an output holds elements its op leaves unspecified (e.g. group_linear's
    // skipped ball padding): copies the reference's values there into the GPU's
    // output, so node-by-node checks compare only what the op defines. Null: none.
    void (*take_unspecified)(const std::vector<const HostTensor*>& in, const Params& p, const HostTensor& ref,
                             HostTensor& gpu_out) = nullptr;
    // Device bytes the GPU recorder needs beyond its outputs on this device (e.g.
    // conv2d's partial sums where it splits a long reduction to fill a big GPU).
    // Null: none. Its choice must be the one gpu() makes for the same device.
    uint64_t (*scratch_bytes)(const rt::DeviceInfo& d, const std::vector<Shape>& in, const Params& p) = nullptr;
};

const OpDef& find_op(std::string_view name);
std::vector<std::string_view> op_names();

}  // namespace vtloc
