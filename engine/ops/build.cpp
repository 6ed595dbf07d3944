#include "engine/ops/build.h"

#include "base/error.h"

namespace vtloc::ops {

namespace {

double flag(bool b) { return b ? 1.0 : 0.0; }
double d(int64_t v) { return double(v); }

}  // namespace

const char* path_name(BufferPath p) { return p == BufferPath::Texel ? "texel" : "storage-buffer"; }

int linear(Graph& g, int x, int w, int bias, Act act, double slope, const std::string& name, bool subgroup, int64_t fill) {
    std::vector<int> in{x, w};
    if (bias >= 0) in.push_back(bias);
    Params p{{"act", double(act)}, {"slope", slope}};
    if (!subgroup) p.set("subgroup", 0);
    if (fill > 0) p.set("fill", d(fill));
    return g.add1("linear", in, p, name);
}

int activation(Graph& g, Act act, int x, double slope, const std::string& name) {
    const char* op = act == kActRelu ? "relu" : act == kActLeaky ? "leaky_relu" : act == kActTanh ? "tanh"
                   : act == kActSigmoid ? "sigmoid" : nullptr;
    if (!op) throw Error("activation: no op for activation code " + std::to_string(act));
    return g.add1(op, {x}, act == kActLeaky ? Params{{"slope", slope}} : Params{}, name);
}

int concat(Graph& g, const std::vector<int>& xs, const std::string& name) { return g.add1("concat", xs, {}, name); }
int flatten(Graph& g, int x, const std::string& name) { return g.add1("flatten", {x}, {}, name); }
int stack(Graph& g, const std::vector<int>& xs, const std::string& name) { return g.add1("stack", xs, {}, name); }
int rows(Graph& g, int x, int64_t start, int64_t count, const std::string& name) {
    return g.add1("rows", {x}, {{"start", double(start)}, {"count", double(count)}}, name);
}

int binary(Graph& g, Binary op, int a, int b, const std::string& name) {
    return g.add1(op == Binary::Add ? "add" : op == Binary::Sub ? "sub" : "mul", {a, b}, {}, name);
}

std::vector<int> cloud_normalize(Graph& g, int cloud, const std::string& name) {
    return g.add("cloud_normalize", {cloud}, {}, name);
}

int conv2d(Graph& g, int x, int w, int bias, int residual, const Conv2d& c, const std::string& name) {
    std::vector<int> in{x, w};
    if (bias >= 0) in.push_back(bias);
    if (residual >= 0) in.push_back(residual);
    Params p{{"stride_h", d(c.stride_h)}, {"stride_w", d(c.stride_w)}, {"pad_h", d(c.pad_h)},
             {"pad_w", d(c.pad_w)}, {"weight_layout", double(c.layout)}, {"act", double(c.act)},
             {"slope", c.slope}, {"residual", flag(residual >= 0)},
             {"texel", flag(c.path == BufferPath::Texel)}};
    if (c.split > 0) p.set("split", d(c.split));
    if (c.c_group > 0) p.set("c_group", d(c.c_group));
    return g.add1("conv2d", in, p, name);
}

int max_pool2d(Graph& g, int x, const Pool2d& p, const std::string& name) {
    return g.add1("max_pool2d", {x},
                  {{"kernel_h", d(p.kernel_h)}, {"kernel_w", d(p.kernel_w)}, {"stride_h", d(p.stride_h)},
                   {"stride_w", d(p.stride_w)}, {"pad_h", d(p.pad_h)}, {"pad_w", d(p.pad_w)},
                   {"texel", flag(p.path == BufferPath::Texel)}},
                  name);
}

int global_avg_pool(Graph& g, int x, const std::string& name) { return g.add1("global_avg_pool", {x}, {}, name); }

int tactile_preprocess(Graph& g, int image, int64_t crop, int64_t size, const std::string& name, BufferPath path) {
    Params p{{"crop", d(crop)}, {"size", d(size)}};
    if (path == BufferPath::Storage) p.set("texel", 0);
    return g.add1("tactile_preprocess", {image}, p, name);
}

int disentangle(Graph& g, const std::vector<int>& in, Act act, double slope, const std::string& name, bool subgroup) {
    Params p{{"act", double(act)}, {"slope", slope}};
    if (!subgroup) p.set("subgroup", 0);
    return g.add1("disentangle", in, p, name);
}

int gma_decode(Graph& g, int x, const std::string& name) { return g.add1("gma_decode", {x}, {}, name); }

std::vector<int> chamfer(Graph& g, int a, int b, const std::string& name, bool subgroup, int queries) {
    Params p;
    if (!subgroup) p.set("subgroup", 0);
    if (queries != 0) p.set("queries", queries);
    return g.add("chamfer", {a, b}, p, name);
}

std::vector<int> ilu(Graph& g, const std::vector<int>& in, int max_iters, const std::string& name, int lanes,
                     bool subgroup, int wave) {
    Params p{{"max_iters", double(max_iters)}};
    if (lanes > 0) p.set("lanes", double(lanes));
    if (!subgroup) p.set("subgroup", 0);
    if (wave != 1) p.set("wave", double(wave));
    return g.add("ilu", in, p, name);
}

std::vector<int> ilu_step(Graph& g, const std::vector<int>& in, int max_iters, int step, const std::string& name) {
    return g.add("ilu_step", in, {{"max_iters", double(max_iters)}, {"step", double(step)}}, name);
}

std::vector<int> ilu_retrieve(Graph& g, const std::vector<int>& in, int max_iters, int candidates, int cloud,
                              int symmetry, int64_t k, const std::string& name, bool fuse, int wave) {
    std::vector<int> all = in;
    all.push_back(candidates);
    all.push_back(cloud);
    if (symmetry >= 0) all.push_back(symmetry);
    Params p{{"max_iters", double(max_iters)}, {"k", d(k)}};
    if (!fuse) p.set("fuse", 0);
    if (wave != 1) p.set("wave", double(wave));
    return g.add("ilu_retrieve", all, p, name);
}

std::vector<int> topk(Graph& g, int contact, int candidates, int64_t k, const std::string& name, bool subgroup) {
    Params p{{"k", d(k)}};
    if (!subgroup) p.set("subgroup", 0);
    return g.add("topk", {contact, candidates}, p, name);
}

int heatmap(Graph& g, int cloud, int candidates, int index, int symmetry, const std::string& name, bool subgroup) {
    std::vector<int> in{cloud, candidates, index};
    if (symmetry >= 0) in.push_back(symmetry);
    Params p;
    if (!subgroup) p.set("subgroup", 0);
    return g.add1("heatmap", in, p, name);
}

std::vector<int> retrieve(Graph& g, int contact, int candidates, int cloud, int symmetry, int64_t k,
                          const std::string& name, bool subgroup) {
    std::vector<int> in{contact, candidates, cloud};
    if (symmetry >= 0) in.push_back(symmetry);
    Params p{{"k", d(k)}};
    if (!subgroup) p.set("subgroup", 0);
    return g.add("retrieve", in, p, name);
}

int pose_evidence(Graph& g, int samples, int dense, int cells, int spins, int terms, int fields,
                  const PoseEvidence& p, const std::string& name) {
    Params q{{"press", p.press}, {"log_floor", p.log_floor}, {"field_floor", p.field_floor}, {"ox", p.origin[0]},
             {"oy", p.origin[1]}, {"oz", p.origin[2]}, {"voxel", p.voxel}, {"nx", d(p.dims[0])},
             {"ny", d(p.dims[1])}, {"nz", d(p.dims[2])}, {"own_field", d(p.own_field)}, {"own_weight", p.own_weight},
             {"texel", flag(p.path == BufferPath::Texel)}, {"interleave", d(p.interleave)}};
    return g.add1("pose_evidence", {samples, dense, cells, spins, terms, fields}, q, name);
}

int gel_gradient(Graph& g, int frame, int empty, int tables, int linear, int64_t n, int64_t tiles_y, int64_t tiles_x, double gentle,
                 const std::string& name) {
    return g.add1("gel_gradient", {frame, empty, tables, linear},
                  {{"n", d(n)}, {"tiles_y", d(tiles_y)}, {"tiles_x", d(tiles_x)}, {"gentle", gentle}}, name);
}

int masked_poisson(Graph& g, int gradient, int mask, int64_t iterations, double omega, const std::string& name, int start) {
    std::vector<int> in{gradient, mask};
    if (start >= 0) in.push_back(start);
    return g.add1("masked_poisson", in, {{"iterations", d(iterations)}, {"omega", omega}},
                  name);  // output 1, the workspace, stays internal
}

int mean_pool2(Graph& g, int x, const std::string& name) { return g.add1("mean_pool2", {x}, {}, name); }

int poisson_prolong(Graph& g, int coarse, int mask, const std::string& name) {
    return g.add1("poisson_prolong", {coarse, mask}, {}, name);
}

int gel_contact_mask(Graph& g, int gradient, double threshold, int64_t close_radius, int64_t open_radius, const std::string& name) {
    return g.add1("gel_contact_mask", {gradient}, {{"threshold", threshold}, {"close_radius", d(close_radius)}, {"open_radius", d(open_radius)}},
                  name);  // output 1, the workspace, stays internal
}

int codebook_render(Graph& g, int samples, int points, int bins, const CodebookRender& p, const std::string& name) {
    return g.add1("codebook_render", {samples, points, bins},
                  {{"G", d(p.G)}, {"cell", p.cell}, {"splat", p.splat}, {"cap", p.cap}, {"facing", p.facing},
                   {"origin_x", p.origin[0]}, {"origin_y", p.origin[1]}, {"origin_z", p.origin[2]}, {"coarse", p.coarse},
                   {"nx", d(p.dims[0])}, {"ny", d(p.dims[1])}, {"nz", d(p.dims[2])}, {"max_bin", d(p.max_bin)}},
                  name);
}

int codebook_window_min(Graph& g, int quads, int spins, int64_t R, int64_t C, double cell, double win, double cap,
                        const std::string& name) {
    return g.add1("codebook_window_min", {quads, spins}, {{"rows", d(R)}, {"cols", d(C)}, {"cell", cell}, {"win", win}, {"cap", cap}},
                  name);
}

int codebook_score(Graph& g, int quads, int spins, int measured, int wmin, int press, double cell, double win, double cap, double weight,
                   bool quadratic, const std::string& name, BufferPath path) {
    return g.add1("codebook_score", {quads, spins, measured, wmin, press},
                  {{"cell", cell}, {"win", win}, {"cap", cap}, {"weight", weight}, {"quadratic", quadratic ? 1.0 : 0.0},
                   {"texel", flag(path == BufferPath::Texel)}},
                  name);
}

std::vector<int> log_softmax(Graph& g, int score, const std::string& name, BufferPath path, int64_t groups) {
    return g.add("log_softmax", {score}, {{"texel", flag(path == BufferPath::Texel)}, {"groups", d(groups)}}, name);
}

int field_slack(Graph& g, int fields, int neighbours, int widths, int64_t n_spin, const std::string& name) {
    return g.add1("field_slack", {fields, neighbours, widths}, {{"n_spin", d(n_spin)}}, name);
}

int spin_marginal(Graph& g, int prob, int64_t n_spin, const std::string& name, BufferPath path) {
    return g.add1("spin_marginal", {prob}, {{"n_spin", d(n_spin)}, {"texel", flag(path == BufferPath::Texel)}}, name);
}

int expected_distance(Graph& g, int points, int weights, int answers, const std::string& name, bool subgroup,
                      BufferPath path) {
    Params p;
    if (!subgroup) p.set("subgroup", 0);
    if (path == BufferPath::Storage) p.set("texel", 0);
    return g.add1("expected_distance", {points, weights, answers}, p, name);
}

std::vector<int> fps(Graph& g, int xyz, int64_t npoint, const std::string& name, bool force_workspace, bool force_tree,
                     int64_t threads) {
    Params p{{"npoint", d(npoint)}};
    if (force_workspace) p.set("no_registers", 1);
    if (force_tree) p.set("subgroup", 0);
    if (threads > 0) p.set("threads", d(threads));
    return g.add("fps", {xyz}, p, name);
}

int ball_query(Graph& g, int xyz, int centres, double radius, int64_t nsample, const std::string& name, bool force_tiles) {
    Params p{{"radius", radius}, {"nsample", d(nsample)}};
    if (force_tiles) p.set("subgroup", 0);
    return g.add1("ball_query", {xyz, centres}, p, name);
}

int point_group(Graph& g, const std::vector<int>& in, int64_t feat_begin, const std::string& name) {
    return g.add1("point_group", in, {{"feat_begin", d(feat_begin)}}, name);
}

int group_max(Graph& g, int x, int64_t group, bool channel_major, const std::string& name) {
    return g.add1("group_max", {x}, {{"group", d(group)}, {"channel_major", flag(channel_major)}}, name);
}

int group_linear(Graph& g, const std::vector<int>& in, const GroupLinear& l, const std::string& name) {
    Params p{{"in", double(l.input)}, {"act", double(l.act)}, {"slope", l.slope},
             {"texel", flag(l.path == BufferPath::Texel)}};
    if (l.weights != GroupLinear::Weights::Shuffle) p.set("weights", double(l.weights));
    if (l.input == GroupLinear::Input::Gather || l.input == GroupLinear::Input::Points) p.set("feat_begin", d(l.feat_begin));
    if (l.max) p.set("max", 1);
    if (l.tile != GroupLinear::Tile::Auto) p.set("tile", double(l.tile));
    if (l.hidden != GroupLinear::Hidden::None) p.set("hidden", double(l.hidden));
    if (l.point_major) p.set("point_major", 1);
    if (l.x_point_major) p.set("x_point_major", 1);
    if (l.rows_in_x) p.set("rows_in_x", 1);
    if (l.row_blocks) p.set("row_blocks", 1);
    if (l.skip_padding) p.set("pad", 1);
    if (l.fill > 0) p.set("fill", d(l.fill));
    if (l.parts > 0) p.set("parts", d(l.parts));
    if (l.max && l.input != GroupLinear::Input::Gather) p.set("group", d(l.group));  // a gather's groups are its balls
    return g.add1("group_linear", in, p, name);
}

int sa_gather(Graph& g, int u, int centres, int idx, int weight_kn, Act act, const std::string& name, BufferPath path) {
    return g.add1("sa_gather", {u, centres, idx, weight_kn}, {{"act", double(act)}, {"texel", flag(path == BufferPath::Texel)}},
                  name);
}

int normal_estimate(Graph& g, int points, int order, int cell_start, const PointGrid& grid, int64_t k, int orient,
                    const std::array<double, 3>& ref, const std::string& name) {
    Params p{{"k", d(k)}, {"orient", double(orient)}, {"rx", ref[0]}, {"ry", ref[1]}, {"rz", ref[2]}};
    set_grid_params(p, grid);
    return g.add1("normal_estimate", {points, order, cell_start}, p, name);
}

}  // namespace vtloc::ops
