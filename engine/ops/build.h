#pragma once
// Typed op constructors: every op's parameters as C++ arguments or a struct,
// so a misspelt or wrongly typed parameter is a compile error. They add the
// node through Graph::add, which also refuses unknown names at run time for
// callers that still pass Params. Each returns the node's outputs.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/graph.h"
#include "engine/ops/common.h"
#include "engine/ops/conv2d.h"
#include "engine/ops/point_grid.h"

namespace vtloc::ops {

// How an op reads its read-only inputs: uniform texel buffers (a gather on CPU
// devices; the op falls back by itself past maxTexelBufferElements) or plain
// storage buffers. Tests and the device self-test sweep every path.
enum class BufferPath { Texel, Storage };
inline constexpr BufferPath kBufferPaths[] = {BufferPath::Texel, BufferPath::Storage};
const char* path_name(BufferPath p);

// Dense and elementwise.
// subgroup = false: gemm.comp's shared-memory tiles even where the shuffle shader applies.
// fill > 0 (tests): the shuffle shader's blocks as a GPU would shrink them to offer this
// many workgroups, on any device.
int linear(Graph& g, int x, int w, int bias, Act act = kActNone, double slope = 0.01, const std::string& name = "",
           bool subgroup = true, int64_t fill = 0);
int activation(Graph& g, Act act, int x, double slope = 0.01, const std::string& name = "");  // relu, leaky_relu, ...
int concat(Graph& g, const std::vector<int>& xs, const std::string& name = "");
// Elementwise with suffix broadcasting.
enum class Binary { Add, Sub, Mul };
int binary(Graph& g, Binary op, int a, int b, const std::string& name = "");
int flatten(Graph& g, int x, const std::string& name = "");
// Along the first axis: stack joins [n_i, ...] tensors, rows takes [start, start + count).
int stack(Graph& g, const std::vector<int>& xs, const std::string& name = "");
int rows(Graph& g, int x, int64_t start, int64_t count, const std::string& name = "");

// Image.
struct Conv2d {
    int64_t stride_h = 1, stride_w = 1, pad_h = 0, pad_w = 0;
    uint32_t layout = kConvOIHW;  // kConvOIHW or kConvIHWO (conv_weight_to_ihwo)
    Act act = kActNone;
    double slope = 0.01;
    BufferPath path = BufferPath::Texel;
    int64_t split = 0;  // > 0: sum the input channels in that many parts (tests; 0: the device's choice)
    int64_t c_group = 0;  // > 0: accumulators a group in the fma chains (tests; 0: the device's choice)
};
// bias, residual: -1 for none.
int conv2d(Graph& g, int x, int w, int bias, int residual, const Conv2d& c, const std::string& name = "");
struct Pool2d {
    int64_t kernel_h = 1, kernel_w = 1, stride_h = 1, stride_w = 1, pad_h = 0, pad_w = 0;
    BufferPath path = BufferPath::Texel;
};
int max_pool2d(Graph& g, int x, const Pool2d& p, const std::string& name = "");
int global_avg_pool(Graph& g, int x, const std::string& name = "");
int tactile_preprocess(Graph& g, int image, int64_t crop, int64_t size, const std::string& name = "",
                       BufferPath path = BufferPath::Texel);

// GMA and heads.
// subgroup = false: the shared-memory slabs even where the device has shuffles.
int disentangle(Graph& g, const std::vector<int>& in, Act act, double slope, const std::string& name = "",
                bool subgroup = true);
int gma_decode(Graph& g, int x, const std::string& name = "");
// subgroup = false: the shared-memory tiled search even where the device has shuffles.
// queries: queries per thread of the shuffle search, 1..8 (0: the device's choice).
std::vector<int> chamfer(Graph& g, int a, int b, const std::string& name = "", bool subgroup = true, int queries = 0);
// lanes: lanes per row of the fused GRU (0: the op's default); subgroup = false
// keeps the row sums in shared memory even where the device has subgroup
// shuffles; wave: 1 = the register-resident shader where it applies, 0 = never,
// >= 2 = it with that workgroup size, an error where it cannot run
// (engine/ops/ilu_math.h).
std::vector<int> ilu(Graph& g, const std::vector<int>& in, int max_iters, const std::string& name = "", int lanes = 0,
                     bool subgroup = true, int wave = 1);
std::vector<int> ilu_step(Graph& g, const std::vector<int>& in, int max_iters, int step, const std::string& name = "");
// ilu then retrieve on its contact, one op (one dispatch where both take their
// register shaders): {c, contact, index, score, heat-map, workspace}. in: the
// ILU's 13 inputs; symmetry: -1 for none; fuse = false: the two ops' own
// dispatches always (tests and the bench compare both).
std::vector<int> ilu_retrieve(Graph& g, const std::vector<int>& in, int max_iters, int candidates, int cloud,
                              int symmetry, int64_t k, const std::string& name = "", bool fuse = true, int wave = 1);
// subgroup = false: the shared-memory sort even where the register shader applies (K <= 16).
std::vector<int> topk(Graph& g, int contact, int candidates, int64_t k, const std::string& name = "",
                      bool subgroup = true);
// symmetry: -1 for none.
// subgroup = false: the two-pass shaders even where the one-subgroup shader applies.
int heatmap(Graph& g, int cloud, int candidates, int index, int symmetry, const std::string& name = "",
            bool subgroup = true);
// topk then heatmap in one op (one dispatch where both take their subgroup
// shaders): {index, score, heat-map, workspace}. symmetry: -1 for none;
// subgroup = false: the two ops' other shaders.
std::vector<int> retrieve(Graph& g, int contact, int candidates, int cloud, int symmetry, int64_t k,
                          const std::string& name = "", bool subgroup = true);

// Multi-touch filter (SPEC 6; engine/track/ builds the grid these read).
struct PoseEvidence {
    double press = 0.8, log_floor = -12, field_floor = -30;
    double origin[3] = {0, 0, 0}, voxel = 1;
    int64_t dims[3] = {1, 1, 1};
    int64_t own_field = -1;  // a field added at the hypothesis itself, -1 none
    double own_weight = 1;
    BufferPath path = BufferPath::Texel;  // the tables as texel buffers where the device allows
    int64_t interleave = 0;  // hypotheses an invocation runs side by side, 1-8 (0: the device's)
};
// samples [S, 12], dense [D, 8], cells [V, 2] I32, spins [NS, 2], terms [K, 16], fields [F, S*NS] -> score [S*NS].
int pose_evidence(Graph& g, int samples, int dense, int cells, int spins, int terms, int fields,
                  const PoseEvidence& p, const std::string& name = "");
// score [M] -> {log probabilities, probabilities}.
// The gel's shape from a frame (SPEC 9): the indentation's gradient from a frame, its empty
// frame and the inverted calibration's tables [tiles_y * tiles_x, n^3, 2]; and the height
// inside a contact mask from that gradient (red-black SOR).
// gentle > 0: where the tables' slope is at most this, linear [H, W, 6]'s inverse instead.
int gel_gradient(Graph& g, int frame, int empty, int tables, int linear, int64_t n, int64_t tiles_y, int64_t tiles_x,
                 double gentle, const std::string& name = "");
int masked_poisson(Graph& g, int gradient, int mask, int64_t iterations, double omega, const std::string& name = "",
                   int start = -1);  // start: a first guess [H, W] (poisson_prolong's), -1: zeros
int mean_pool2(Graph& g, int x, const std::string& name = "");
int poisson_prolong(Graph& g, int coarse, int mask, const std::string& name = "");
// The contact mask [H, W] (exact 0/1) from that gradient (engine/ops/gel_mask.h): the 3x3 mean slope
// above threshold, closed, holes filled, opened (disc radii, 0: none), the largest piece.
int gel_contact_mask(Graph& g, int gradient, double threshold, int64_t close_radius, int64_t open_radius,
                     const std::string& name = "");
// groups > 0 (tests): that many chunks, each a workgroup, instead of the device's fill.
std::vector<int> log_softmax(Graph& g, int score, const std::string& name = "", BufferPath path = BufferPath::Texel,
                             int64_t groups = 0);
// prob [S * n_spin] -> [S].
int spin_marginal(Graph& g, int prob, int64_t n_spin, const std::string& name = "", BufferPath path = BufferPath::Texel);
// points [S, 3], weights [S], answers [A, 3] -> sum_s w_s ||p_s - a_j|| [A].
// subgroup = false: the shared-memory tiles even where the device has shuffles; path: how the
// shuffle shader reads the points and weights.
int expected_distance(Graph& g, int points, int weights, int answers, const std::string& name = "", bool subgroup = true,
                      BufferPath path = BufferPath::Texel);
// fields [F, S * n_spin], neighbours [S, KN, 3], widths [F, 2] -> fields widened by odometry slack
// (engine/ops/field_slack.cpp).
int field_slack(Graph& g, int fields, int neighbours, int widths, int64_t n_spin, const std::string& name = "");
// Render-and-compare (SPEC 9; engine/ops/codebook_math.h says how). The binning of the
// dense points: origin, cell size `coarse`, dims, and the largest bin's count.
struct CodebookRender {
    int64_t G = 26;
    double cell = 1, splat = 0.75, cap = 8, facing = 0.3;
    double origin[3] = {0, 0, 0}, coarse = 1;
    int64_t dims[3] = {1, 1, 1};
    int64_t max_bin = 1;
};
// samples [S, 9], points [D, 6] (binned), bins [nx*ny*nz, 2] I32 -> heights [S, G*G].
int codebook_render(Graph& g, int samples, int points, int bins, const CodebookRender& p, const std::string& name = "");
// quads [S, 4 (G+1)^2] (each map's bilinear quads, book::make_quads), spins [NS, 2] -> [S*NS]:
// each hypothesis' shallowest depth under a window of R x C cells of `win` mm (once per
// window size; codebook_score reads it).
int codebook_window_min(Graph& g, int quads, int spins, int64_t R, int64_t C, double cell, double win, double cap,
                        const std::string& name = "");
// quads [S, 4 (G+1)^2], spins [NS, 2], measured [R, C] (cells of `win` mm), wmin [S*NS]
// (codebook_window_min of the same window), press [1] (book::measured_press of the map)
// -> log term [S*NS]; quadratic: the error also loses its r^2, c^2, r c fit.
int codebook_score(Graph& g, int quads, int spins, int measured, int wmin, int press, double cell, double win, double cap, double weight,
                   bool quadratic = false, const std::string& name = "", BufferPath path = BufferPath::Texel);

// Point cloud.
// force_workspace: the shared-memory/workspace path even where the registers
// path would fit; force_tree: the shared-memory tree reduction even where the
// device has subgroup arithmetic (tests and the self-test cover all of them).
// The normalised frame on the GPU: outputs the cloud and the frame [4].
std::vector<int> cloud_normalize(Graph& g, int cloud, const std::string& name = "");
// threads > 0: the workgroup size (a power of two; tests and the bench's variants).
std::vector<int> fps(Graph& g, int xyz, int64_t npoint, const std::string& name = "", bool force_workspace = false,
                     bool force_tree = false, int64_t threads = 0);
// force_tiles: the shared-memory tiles even where the device has subgroup shuffles.
int ball_query(Graph& g, int xyz, int centres, double radius, int64_t nsample, const std::string& name = "",
               bool force_tiles = false);
// in: points, centres, ball indices (+ features); feat_begin: first feature column.
int point_group(Graph& g, const std::vector<int>& in, int64_t feat_begin, const std::string& name = "");
int group_max(Graph& g, int x, int64_t group, bool channel_major, const std::string& name = "");
struct GroupLinear {
    enum class Input { Rows = 0, Gather = 1, GroupAll = 2, Points = 3 } input = Input::Rows;
    int64_t feat_begin = 0;  // Gather, Points: first feature column
    bool max = false;        // keep only the max over each group of `group` rows
    int64_t group = 1;
    Act act = kActNone;
    double slope = 0.01;
    BufferPath path = BufferPath::Texel;
    // How the weights reach the lanes on the Texel path (group_linear.cpp); each falls
    // back to the next where the device lacks what it needs. Tests sweep all three.
    enum class Weights { Shuffle = 0, Uniform = 1, Storage = 2 } weights = Weights::Shuffle;
    // Auto: chosen per device and layer (CPU devices: 8 x 32 on big layers,
    // group_linear.cpp). The others force a big-layer tile whatever the layer or
    // device: 16 x 32 (the earlier choice with 16 host vector registers) or 8 x 32;
    // tests and the self-test reach both.
    enum class Tile { Auto = 0, Big16x32 = 1, Big8x32 = 2 } tile = Tile::Auto;
    // Gather only: the layer's input is a first layer computed in registers from
    // the ball rows, never stored (the same act; W0's width a multiple of 4):
    //   Gathered: [points, centres, idx, W0^T, b0, W^T, bias (, features)], act(row W0^T + b0)
    //     of the gathered row (<= 4 features);
    //   PerPoint: [U, centres, idx, W0^T, W^T, bias], act(U[q] - W0^T's xyz rows . centre),
    //     U = group_linear(Points, point_major) of W0 (sa_gather's arithmetic).
    enum class Hidden { None = 0, Gathered = 1, PerPoint = 2 } hidden = Hidden::None;
    bool point_major = false;  // a plain output as [M, N] instead of [N, M]
    // Rows only: x is point-major [M, K] (a layer before with point_major) instead of
    // channel-major [K, M]. On a CPU driver a lane then reads its own rows' channels
    // as contiguous vec4s, where channel-major rows sit a whole row of M apart per
    // channel (docs/performance.md "Point-major rows").
    bool x_point_major = false;
    // The workgroup grid: channel blocks along x where the device's limits allow
    // (group_linear.cpp says why); true keeps row blocks along x (tests run both).
    bool rows_in_x = false;
    // Ball padding (SPEC 2: free slots repeat the ball's first index) skipped:
    // left out of a max (Gather, or Rows with the ball as a last input, idx
    // [M / group, group]), unspecified in a plain Gather output; the max must then
    // take it too. The point encoder sets it on the max and the gathering layer
    // right before it.
    bool skip_padding = false;
    // skip_padding on a plain output: one invocation per row block, as on a GPU, also
    // on a CPU device, where a ball's chunks are otherwise pooled (tests run both).
    bool row_blocks = false;
    // > 0: the tiles a GPU would shrink to so as to offer this many workgroups, on any
    // device (tests: lavapipe runs what a big GPU runs).
    int64_t fill = 0;
    // max on the Shuffle path, > 1: lanes per group, a power of two up to the subgroup
    // size (tests; 0: the device's choice, which a GPU's rule may raise).
    int64_t parts = 0;
};
int group_linear(Graph& g, const std::vector<int>& in, const GroupLinear& l, const std::string& name = "");
// The weight path group_linear takes on device `d` for a K x N weight at byte
// `offset`, asked for `want` (exposed so tests can tell which one ran).
GroupLinear::Weights group_linear_weight_path(const rt::DeviceInfo& d, int64_t K, int64_t N, bool texel,
                                              GroupLinear::Weights want, uint64_t offset);
// Layer one of a set-abstraction MLP from its per-point part u = group_linear
// (Points) of the same weight (sa_gather.cpp): rows of the ball `idx` around `centres`.
int sa_gather(Graph& g, int u, int centres, int idx, int weight_kn, Act act, const std::string& name = "",
              BufferPath path = BufferPath::Texel);
// Normals from the k nearest points found through `grid` (point_grid.h);
// orient: 0 as computed, 1 away from `ref` (a centroid), 2 towards it (a camera).
int normal_estimate(Graph& g, int points, int order, int cell_start, const PointGrid& grid, int64_t k, int orient,
                    const std::array<double, 3>& ref, const std::string& name = "");

}  // namespace vtloc::ops
