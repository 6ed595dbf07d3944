// gel_contact_mask (SPEC 9, docs/gel_shape.md step 4): gradient [H, W, 2] -> the contact [H, W]
// (exact 0/1) and a workspace (unspecified); params threshold, close_radius, open_radius (0..64).
// CPU reference: engine/ops/gel_mask.h. -> shaders/gel_contact_mask.comp, one stage a dispatch
// (11 to 15): the slope threshold, the closing's dilation and erosion, a hole fill, the opening,
// the largest piece, a hole fill again. Hole fill and labelling are union-find over runs (join,
// then roots read back): a fixed dispatch count and no loop to convergence, which on lavapipe
// would also meet its per-invocation loop limit on a long winding piece.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/error.h"
#include "engine/ops/common.h"
#include "engine/ops/gel_mask.h"
#include "engine/ops/ops.h"

namespace vtloc::ops {
namespace {

constexpr int kMaxRadius = 64;

// The shader's stages (shaders/gel_contact_mask.comp).
enum Stage : uint32_t {
    kSlope = 0, kDilate = 1, kErode = 2, kJoinBackground = 3, kJoinForeground = 4, kMarkOutside = 5, kFillHoles = 6,
    kFillHolesOut = 7, kCount = 8, kFirstLargest = 9, kKeepLargest = 10
};

// The workspace in 32-bit words: bit images A and B (rows of ceil(W / 32) words), two union-find
// sets (parents [H W], counts [H W]), the largest count and its root.
struct Layout {
    uint32_t a, b, x, y, top, total;
};
Layout layout(int64_t H, int64_t W) {
    const int64_t words = H * ((W + 31) / 32), HW = H * W;
    to_u32(2 * words + 4 * HW + 2, "gel_contact_mask workspace size");
    return {0, uint32_t(words), uint32_t(2 * words), uint32_t(2 * words + 2 * HW), uint32_t(2 * words + 4 * HW),
            uint32_t(2 * words + 4 * HW + 2)};
}

int radius_param(const Params& p, const char* k) {
    const double v = p.get(k, -1);
    if (!(v >= 0 && v <= kMaxRadius) || v != std::floor(v)) {
        std::ostringstream got;
        got << v;
        throw Error(std::string("gel_contact_mask: ") + k + " must be an integer in [0, " + std::to_string(kMaxRadius) +
                    "], got " + got.str());
    }
    return int(v);
}

std::vector<TensorDesc> infer(const std::vector<TensorDesc>& in, const Params& p) {
    expect_input_count(in, 1, 1);
    expect_f32(in);
    radius_param(p, "close_radius"), radius_param(p, "open_radius");
    if (!std::isfinite(p.get("threshold", NAN))) throw Error("gel_contact_mask: threshold must be a finite number");
    const Shape& g = in[0].shape;
    if (g.size() != 3 || g[2] != 2 || g[0] < 1 || g[1] < 1)
        throw Error("gel_contact_mask: the gradient must be [H, W, 2], got " + shape_str(g));
    return {TensorDesc{{g[0], g[1]}}, TensorDesc{{int64_t(layout(g[0], g[1]).total)}, ElemType::I32}};
}

void cpu(const std::vector<const HostTensor*>& in, const std::vector<HostTensor*>& out, const Params& p) {
    const int H = int(in[0]->shape[0]), W = int(in[0]->shape[1]);
    const std::vector<uint8_t> m = gel::contact_mask(in[0]->data.data(), H, W, float(p.get("threshold", 0)),
                                                     int(p.get("close_radius", 0)), int(p.get("open_radius", 0)));
    for (size_t q = 0; q < m.size(); ++q) out[0]->data[q] = m[q];
    std::fill(out[1]->data.begin(), out[1]->data.end(), 0.0f);
}

void gpu(const GpuOpArgs& a) {
    const rt::DeviceInfo& d = a.ctx.info();
    const int32_t H = int32_t(a.in[0].shape[0]), W = int32_t(a.in[0].shape[1]);
    const Layout ws = layout(H, W);
    const uint32_t words = ws.b, local = elementwise_local_size(d), groups = grid_groups(words, local, d);
    const int32_t close_r = int32_t(a.params.get("close_radius", 0)), open_r = int32_t(a.params.get("open_radius", 0));
    // A lane's longest loop: its words times the larger of a word's pixels and the disc's shifts.
    const uint64_t lanes = uint64_t(groups) * local, per = (words + lanes - 1) / lanes, r = uint64_t(std::max(close_r, open_r));
    check_loop_budget(d, per * std::max<uint64_t>(32, (2 * r + 1) * (2 * r + 1)), "gel_contact_mask");
    const std::vector<rt::Binding> bind{{a.in[0].view, rt::Access::Read}, {a.out[0].view, rt::Access::Write},
                                        {a.out[1].view, rt::Access::ReadWrite}};
    const float threshold = float(a.params.get("threshold", 0));
    constexpr uint32_t kNone = 0xffffffffu;
    // src, dst: images; uf: the stage's union-find set; init: the set to reset from the word written.
    auto stage = [&](Stage s, uint32_t src, uint32_t dst, uint32_t uf, uint32_t init, int32_t radius = 0) {
        struct {
            int32_t H, W, radius;
            uint32_t src, dst, uf, init, top;
            float threshold;
        } push{H, W, radius, src, dst, uf, init, ws.top, threshold};
        a.seq.dispatch(pipeline(a.ctx, "gel_contact_mask", 3, sizeof(push), {local, s}), bind, &push, sizeof(push), groups);
    };
    // Each set is reset by the image stage before the union-find that uses it: X for the hole
    // fills, Y for the labelling.
    stage(kSlope, 0, ws.a, 0, close_r > 0 ? kNone : ws.x);
    if (close_r > 0) stage(kDilate, ws.a, ws.b, 0, kNone, close_r), stage(kErode, ws.b, ws.a, 0, ws.x, close_r);
    stage(kJoinBackground, ws.a, 0, ws.x, kNone), stage(kMarkOutside, ws.a, 0, ws.x, kNone);
    stage(kFillHoles, ws.a, ws.a, ws.x, open_r > 0 ? kNone : ws.y);
    if (open_r > 0) stage(kErode, ws.a, ws.b, 0, kNone, open_r), stage(kDilate, ws.b, ws.a, 0, ws.y, open_r);
    for (Stage s : {kJoinForeground, kCount, kFirstLargest}) stage(s, ws.a, 0, ws.y, kNone);
    stage(kKeepLargest, ws.a, ws.a, ws.y, ws.x);
    stage(kJoinBackground, ws.a, 0, ws.x, kNone), stage(kMarkOutside, ws.a, 0, ws.x, kNone), stage(kFillHolesOut, ws.a, 0, ws.x, kNone);
}

}  // namespace

const OpDef op_gel_contact_mask{"gel_contact_mask", infer, cpu, gpu, 1u << 1, {"threshold", "close_radius", "open_radius"}};

}  // namespace vtloc::ops
