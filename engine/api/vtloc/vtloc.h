#pragma once
// VTLoc: visual-tactile contact localisation on the GPU (Vulkan compute).
// The public C++ API, installed as <vtloc/vtloc.h>; link vtloc::vtloc
// (find_package(vtloc)). Standard library only: no Vulkan, JSON or engine
// headers leak through it.
//
// A minimal program:
//
//   vtloc::api::Context ctx;                                  // best device
//   vtloc::api::Model model(ctx, "model.safetensors");
//   vtloc::api::Object mug = model.encode_object("mug.glb");  // point branch, once
//   vtloc::api::TouchResult r = model.localize(mug, vtloc::api::load_tactile_image("touch.png"));
//   // r.contact: where the touch was, in the mesh's units; r.heatmap: per point of mug.cloud()
//
// Errors: every failure (bad file, bad input, out of memory, Vulkan error)
// throws vtloc::api::Error, whose what() is one line naming the problem (and
// the file, where there is one). No other exception type escapes the API.
// A moved-from Context or Model may only be destroyed or assigned to.
//
// Thread-safety:
// - No global state: every resource hangs off a Context (its own Vulkan
//   instance, device and queue) or a Model.
// - A Model (and its Context) may be shared between threads: the calls on one
//   Model run one at a time (encode_object, localize: a lock), and
//   the Context serialises its queue. For parallel work make one Context (and
//   Model) per thread; contexts share nothing, and concurrent contexts on one
//   device give bit-identical results to a single one (both tested, 4 threads).
// - Trackers of one object (one and those its with_options made) may run on
//   different threads at once: what they share (the device tables, the codebook,
//   the binned points) is made once, by whichever needs it first, under a lock
//   (tested: two threads, bit for bit a tracker alone's results; TSan in CI).
//   The calls on one Tracker run one at a time (a lock): one thread may read
//   its estimate or belief while another adds a touch (tested; Python
//   releases the GIL while a touch is added).
// - A GelShapeReader may be shared too: its reads take turns (a lock).
// - An Object is immutable once made: it may be read from any thread and used
//   by any Model loaded from the same weight file (another file's Model
//   refuses it).
// - The free functions (list_devices, inspect_model, load_*, write_*, render_*,
//   save_tensors) touch no shared state and may run concurrently.
#include <array>
#include <limits>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "check.h"  // check and check_ops: a device against the CPU reference

namespace vtloc::api {

// Library version (the CMake project version).
const char* version();

// Run-time limits of every model (the engine's own, engine/model/model_config.h;
// checked equal at build time): ILU iterations and top-K size.
inline constexpr int kMaxIterations = 64;
inline constexpr int kMaxTopK = 256;

// The one exception type of the API.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// ---- Devices and contexts -------------------------------------------------

struct DeviceInfo {
    int index = 0;                // Vulkan enumeration order
    std::string name;
    std::string type;             // "discrete GPU", "integrated GPU", "CPU", ...
    int api_major = 0, api_minor = 0;
    uint32_t subgroup_size = 0;
    uint32_t shared_memory_bytes = 0;       // per workgroup
    uint32_t max_workgroup_invocations = 0;
    std::array<uint32_t, 3> max_workgroup_size{};
    std::array<uint32_t, 3> max_workgroup_count{};
    uint64_t max_storage_buffer_bytes = 0;  // one binding
    uint32_t max_storage_buffers = 0;       // per shader stage
    uint32_t max_push_constant_bytes = 0;
    uint32_t max_texel_buffer_elements = 0;
    bool timestamps = false;                // per-node GPU timing possible
    uint64_t device_local_bytes = 0;
    // CPU devices (lavapipe): vector registers of the host CPU its JIT code runs on,
    // 32 with AVX-512VL or on AArch64, else 16 (16 where GALLIUM_OVERRIDE_CPU_CAPS holds
    // Mesa's JIT below AVX-512); a CPU driver's speed depends on it. 0 on GPUs.
    uint32_t host_vector_registers = 0;
    // GPUs: NVIDIA SMs, AMD CUs or Arm shader cores where the driver says; 0: unknown.
    uint32_t compute_units = 0;
};

// Every Vulkan device with a compute queue.
std::vector<DeviceInfo> list_devices();
// The limits of device `index` (list_devices' index) as a device profile, JSON text
// (format vtloc-device-profile/1): `vtloc-bench --plan-for FILE` makes the engine's
// choices for that device on another machine (docs/performance.md).
std::string device_profile(int index);

enum class Validation {
    Environment,  // on when VTLOC_VALIDATION is 1/on/true/yes
    Off,
    On,           // Khronos validation layer; throws if it is not installed
};

struct ContextOptions {
    // "" = the VTLOC_DEVICE environment variable if set, else the best device
    // (discrete > integrated > CPU); digits = a device index; anything else =
    // a case-insensitive substring of the device name.
    std::string device;
    Validation validation = Validation::Environment;
    // Bytes of GPU buffers this context may hold at once (0: the environment's
    // VTLOC_MEMORY_BUDGET_MIB, else no limit): past it, work fails with a clear
    // out-of-device-memory error and the context stays usable. For robots that
    // share a GPU, and for testing how a program handles the failure.
    uint64_t memory_budget = 0;
};

// Destroy a context before main() returns. One held by a namespace-scope object
// (a global smart pointer filled later) is destroyed by exit() after the exit
// handlers the driver registered when the context loaded it, and NVIDIA's
// driver crashes then.
class Context {
public:
    explicit Context(const ContextOptions& options = {});
    ~Context();
    Context(Context&&) noexcept;
    Context& operator=(Context&&) noexcept;

    const DeviceInfo& device() const;
    bool validation_enabled() const;
    // Validation-layer warnings and errors since the last call (one string each).
    std::vector<std::string> take_validation_messages();
    // Bytes of GPU buffers (device and staging) this context holds now: weights,
    // activations and staging of every model run on it.
    uint64_t memory_in_use() const;

    struct Impl;

private:
    friend class Model;
    friend struct ContextAccess;  // engine/api internals (check, check_ops)
    std::unique_ptr<Impl> impl_;
};

// ---- Models -----------------------------------------------------------------

struct TensorSummary {
    std::string name;
    std::string dtype;            // as stored: "F32", "F16", "I64", ...
    std::vector<int64_t> shape;
};

// The sensor a model was trained on (the config's optional "sensor" section).
struct SensorInfo {
    double mm_per_px = 0;         // pixel size, mm
    int height = 0, width = 0;    // frame size, pixels
};

struct ModelInfo {
    std::string path;
    std::string name;             // config name, e.g. "vtloc-r18"
    std::string config_json;      // the whole config (SPEC section 7), pretty-printed
    std::string head;             // "ilu" or "mcr"
    int64_t feature_size = 0;     // C
    int64_t default_k = 0;        // K
    int default_iters = 0;        // ILU iterations N (0 for the MCR head)
    bool use_normals = false;
    bool has_gma = false;
    int64_t crop = 0, input_size = 0;  // tactile preprocessing
    int64_t sample_points = 0;    // points sampled from a mesh (point.n_points)
    int64_t min_points = 0;       // fewest cloud points the model accepts
    std::optional<SensorInfo> sensor;  // absent: the config records none (no rescaling)
    uint64_t parameter_count = 0; // float elements: weights and BatchNorm statistics
    double size_mib = 0;          // parameter_count as fp32, in MiB
    uint64_t file_bytes = 0;
    std::vector<TensorSummary> tensors;  // in file order
};

// Reads and checks a weight file without any GPU: the config is complete and
// every tensor the network needs is present with its shape.
ModelInfo inspect_model(const std::string& path);

enum class Backend { Gpu, Cpu };  // Cpu: the plain C++ reference ops (slow; for checking)

// Objects: the object point cloud P in object units. xyz and normals hold 3
// floats per point; normals are scaled to unit length (a zero normal is an
// error). Empty normals: estimated at encode_object (k = 16 nearest points and
// PCA, oriented towards `viewpoint` when set, else away from the centroid;
// Object::normals_estimated says so). Clouds of 100,000 points or more are
// reduced at encode_object: a voxel grid to ~4 x the model's point count, then
// farthest point sampling to that count (Object::source_points keeps N).
struct PointCloud {
    std::vector<float> xyz;
    std::vector<float> normals;
    std::optional<std::array<double, 3>> viewpoint;  // e.g. the camera that saw the points
    size_t size() const { return xyz.size() / 3; }
};

// Meshes (.glb .gltf .obj .off .stl, .ply with faces): area-weighted surface
// samples (n_points, fixed seed). Point clouds (.ply, .pcd, .xyz/.csv/.txt
// rows): the file's points, whatever their number, with normals when the file
// has them (nx ny nz; PCD normal_x..), else with empty normals.
PointCloud load_point_cloud(const std::string& path, int64_t n_points, uint64_t seed = 0);
// A depth camera's view: a 16-bit PNG (value * unit_mm = depth in mm, 0 = none),
// intrinsics fx, fy, cx, cy (pixels), an optional mask image (nonzero = the
// object). -> the partial cloud in the camera frame (mm; x right, y down, z
// forward), no normals, viewpoint = the camera (0, 0, 0).
PointCloud load_depth_cloud(const std::string& depth_path, const std::array<double, 4>& intrinsics,
                            const std::string& mask_path = "", double unit_mm = 1.0);
// Candidate contact points (3 floats each): a .ply's vertices or a text file
// of x,y,z rows (see engine/io/candidates.h).
std::vector<float> load_candidates(const std::string& path);

// An object ready for touches: its cloud, candidates, normalised frame and the
// point branch's feature. Cheap to copy (shared, immutable).
class Object {
public:
    Object();
    ~Object();
    Object(const Object&);
    Object& operator=(const Object&);

    const std::string& source() const;         // file it came from ("" for arrays)
    const PointCloud& cloud() const;           // object units
    const std::vector<float>& candidates() const;  // object units, 3 per candidate
    size_t candidate_count() const;
    std::array<double, 3> centre() const;      // normalised frame: (p - centre) / scale
    double scale() const;
    bool normals_estimated() const;            // the input had no normals: cloud() holds estimated ones
    size_t source_points() const;              // points in the input (before a large cloud's reduction)

    struct Impl;

private:
    friend class Model;
    std::shared_ptr<const Impl> impl_;
};

// Tactile images: 8-bit RGB, row-major, height x width x 3.
struct TactileImage {
    int height = 0, width = 0;
    std::vector<uint8_t> rgb;
};
TactileImage load_tactile_image(const std::string& path);

// A frame taken with pixels of image_mm_per_px resampled to pixels of
// model_mm_per_px, so that one pixel covers the same millimetres: the size is
// round(H * s) x round(W * s) (halves up), s = image_mm_per_px / model_mm_per_px,
// the centres line up and one output pixel spans exactly 1/s input pixels.
// Shrinking (s < 1) averages the area each output pixel covers (clipped to the
// frame); enlarging (s > 1) is bilinear between pixel centres, clamped at the
// edges. Rows, then columns, in double; rounded to uint8 (halves up). Equal
// sizes return the frame unchanged. Op for op weights_tools.tactile.rescale.
// Both sizes must be finite and > 0; the result must be at least 8 x 8.
TactileImage rescale_tactile_image(const TactileImage& image, double image_mm_per_px, double model_mm_per_px);

struct Symmetry {
    std::array<double, 3> axis_point{0, 0, 0};  // object units
    std::array<double, 3> axis_dir{0, 0, 1};
    int order = 1;                               // M rotations of 360/M degrees
};

struct LocalizeOptions {
    int iters = -1;      // ILU iterations 0..64; -1 = the model's default
    int top_k = 0;       // 1..min(256, candidates); 0 = the model's K
    bool gma = true;     // run GMA for the alignment score (skip for speed)
    std::optional<Symmetry> symmetry;
    Backend backend = Backend::Gpu;
    bool keep_tensors = false;  // fill TouchResult::tensors (every intermediate)
    bool profile = false;       // per-node GPU times (GPU with timestamps only)
    // The frames' pixel size in mm: each frame is first rescaled to the model's
    // sensor.mm_per_px (rescale_tactile_image), before the centre crop. Needs a
    // model whose config records a sensor; finite and > 0. Unset: no rescale.
    std::optional<double> mm_per_px;
};

struct Timings {
    double wall_ms = 0;  // the call on the host; a batch's touches share one run.
                         // The first call of a shape also compiles its pipelines.
    double gpu_ms = 0;   // sum of the node times (profile only)
    std::vector<std::pair<std::string, double>> nodes;  // per graph node (profile only)
};

// A tensor under its SPEC section 8 name (shapes as weights_tools.golden
// writes them; index tensors are I32, the rest F32).
struct Tensor {
    std::string name;
    std::vector<int64_t> shape;
    std::vector<float> f32;       // float tensors
    std::vector<int32_t> i32;     // index tensors
    std::vector<uint8_t> u8;      // input.tactile, tactile.rescaled
};

struct TouchResult {
    std::array<double, 3> contact{};             // c^p, object units
    std::array<double, 3> contact_normalised{};  // c^p, normalised frame
    std::vector<std::array<double, 3>> iterates;            // c_1..c_N, object units (ILU)
    std::vector<std::array<double, 3>> iterates_normalised;
    std::vector<int32_t> topk_index;             // into Object::candidates(), best first
    std::vector<float> topk_score;               // ||c^p - c_i||^2, normalised frame
    std::vector<std::array<double, 3>> topk_point;          // those candidates, object units
    std::vector<float> heatmap;                  // per Object::cloud() point, in [0, 1]
    std::optional<float> alignment;              // chamfer(P^d, P) when GMA ran (lower = better)
    Timings timings;
    std::vector<Tensor> tensors;                 // with keep_tensors
};

class Model {
public:
    // Loads and checks the weight file (inspect_model's checks). The Context
    // must outlive the Model.
    Model(Context& context, const std::string& path);
    // CPU-only model (Backend::Gpu calls throw): no Vulkan needed.
    explicit Model(const std::string& path);
    ~Model();
    Model(Model&&) noexcept;
    Model& operator=(Model&&) noexcept;

    const ModelInfo& info() const;

    // Runs the point branch once. A mesh is sampled to info().sample_points;
    // a cloud without normals gets estimated ones (on this backend);
    // candidates "" = the cloud's own points.
    Object encode_object(const std::string& object_path, const std::string& candidates_path = "",
                         Backend backend = Backend::Gpu);
    // candidates: 3 floats each, object units; empty = the cloud's own points.
    Object encode_object(const PointCloud& cloud, const std::vector<float>& candidates = {},
                         Backend backend = Backend::Gpu);

    TouchResult localize(const Object& object, const TactileImage& image, const LocalizeOptions& options = {});
    // A batch: images of one size run in one submit (sizes may differ; each
    // size is one run).
    std::vector<TouchResult> localize(const Object& object, const std::vector<TactileImage>& images,
                                      const LocalizeOptions& options = {});

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

// ---- Several touches (SPEC section 6) ---------------------------------------

// A rigid motion (R row-major, then t, object units). As the motion between two
// touches: pose b in pose a's frame (R = R_a^T R_b, t = R_a^T (t_b - t_a)), what
// a robot's kinematics measure. As a sensor pose: the columns of R are the
// sensor's x (image columns), y (rows) and z (its axis, into the object) in
// object coordinates, t the window centre on the undeformed gel.
struct Motion {
    std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::array<double, 3> t{};
};
// a then b in a's frame; the inverse. motion_between(a, b) = inverse(a) * b.
Motion compose(const Motion& a, const Motion& b);
Motion inverse(const Motion& a);
// Relative motions from absolute flange poses (robot base frame, metres or mm
// as given): sensor_k = flange_k * tool; motion k = inverse(sensor_k) * sensor_{k+1}.
std::vector<Motion> motions_from_flange_poses(const std::vector<Motion>& flange, const Motion& tool);

struct TrackerOptions {
    double press_mm = 0.8;       // the press assumed for every touch (our data: 0.3-1.5 mm)
    double sigma_d_mm = 1.0;     // a pose's distance to the surface (fitted on train windows: docs/multitouch.md)
    double sigma_a_deg = 6;      // its axis against the inward normal (fitted likewise)
    double odometry_mm = 0;      // motion noise per step (std), widening with the lever arm
    double odometry_deg = 0;
    int window = 8;              // touches scored exactly; older ones enter as a prior
    int n_spin = 36;             // spin hypotheses (10 degrees apart)
    int64_t hypotheses = 120000; // surface samples x spins, about
    double network_weight = 0.5; // temperature of the network's heat-map term (add_touch with a TouchResult)
    // Render-and-compare (SPEC 9): the inverse temperature of a touch's measured gel shape
    // against what each hypothesis would press (add_touch with a GelShape; fitted on train windows).
    double render_weight = 0.25;
    // Whether the comparison also ignores a bowl (r^2, c^2, r c) in the error besides the
    // plane: the shape a frame's integrated slopes bend into (fitted on train windows).
    bool render_quadratic = true;
    // The measured press: this percentile of the cells the gel shape shows pressed (its
    // deepest cell is where the reader's noise and integration error add most; fitted).
    double render_press_percentile = 70;
    // The comparison's cells (mm): the measured map is averaged onto them and each
    // hypothesis' map read at their centres; larger cells, fewer reads (fitted on train
    // windows: 3 mm scored as well as 1 mm, with a ninth of the reads).
    double render_cell_mm = 3.0;
    // Render-and-compare again at the refined poses (0: off): once the filter has climbed its
    // best modes to continuous poses, each touch's gel shape is compared with what the object
    // presses at that very pose (not at the grid's nearest hypothesis, up to half a spacing
    // and a spin step away), and this inverse temperature times that score joins the mode's
    // fit where the modes share the belief; the best 4 modes also climb on it. Fitted on train
    // windows (docs/render_compare.md, "At the refined poses").
    double render_refined_weight = 16;
    // The floor of one touch's score at a refined pose (log; -inf: none): a touch whose map
    // disagrees badly costs at most about this, as a geometry term's floor (-9) bounds a
    // touch off the model, so one misread frame cannot veto the place the others agree on
    // (fitted on train windows: docs/render_compare.md, "A floor at the refined poses").
    double render_refined_floor = -5;
    // With odometry noise (odometry_mm, odometry_deg > 0), each earlier touch's gel shape is
    // compared where it matches best within the noise's widths (a shift along the gel and a spin,
    // each paying its Gaussian prior), found in this many rounds of a pattern search; 0: at the
    // pose the motions carry it to. No effect without noise.
    int render_slack_rounds = 2;
    // With odometry noise, the hypothesis grid reads each earlier touch's term (render-and-compare,
    // the network's heat-map; online, the belief before the window) where it is best among the
    // neighbouring hypotheses, each offset paying its Gaussian prior at the noise's widths;
    // false (the default, fitted on train windows: docs/render_compare.md, "The grid's terms
    // widened"): at the nearest hypothesis the motions lead to. No effect without noise.
    bool field_slack = false;
    // Where the object's codebook (the height maps render-and-compare needs) is cached: read
    // when present and made for this object and these options (else an error naming it),
    // written after the first render. Empty: rendered in memory at the first GelShape.
    std::string codebook_cache;
    double mode_radius_mm = 5;   // the modes' non-maximum suppression
    double grid_allowance = 0.25; // the grid's widths grow by this share of its spacing and spin step (fitted)
    // > 0: each mode is refined at the grid's widths times this first, then at the tight
    // ones (a wider basin for modes several degrees off; fitted on train windows).
    double refine_widen = 0;
    // > 0: each mode is also refined from the nearest touches outward (the window's touches
    // within this lever arm first, then twice it, ...), keeping the better fit: at long lever
    // arms a pose a spin step off finds no slope at the far touches (20 fitted on train
    // windows; 0: the direct climb alone).
    double refine_reach_mm = 20;
    // When the best refined mode fits the window below rescue_fit (log; -inf: never; 0:
    // always, a fit being at most 0), the next rescue_modes modes are refined too (each
    // credited only while its refined pose stays near its own place). -1 and 24 are fitted
    // on train windows (-1 and 0 tied; -1 refines fewer); where it fires an estimate takes
    // about 2.7 ms more on one thread, 1 ms on two (docs/multitouch.md, "Refining more modes").
    double rescue_fit = -1;
    int rescue_modes = 24;
    // > 0: where the best refined mode fits below rescue_fit, the first modes are also
    // registered onto the surface in this many Gauss-Newton rounds (each touch's contact
    // matched to the nearest facing surface point at any distance), climbed again, and the
    // better fit kept: at long lever arms a pose a few degrees off carries the far touches
    // beyond the climb's reach. 12 fitted on train windows (docs/multitouch.md,
    // "Registration"); 0: off.
    int register_rounds = 12;
    // Where the best refined mode still fits below deep_fit (log; -inf: never) after that, the
    // search has lost the touch: every mode not yet refined is registered from its best spin
    // and the deep_modes best by fit are refined too (the truth's mode can rank anywhere on the
    // grid then). -5 and 8 fitted on train windows (docs/multitouch.md, "Deep search"); it
    // costs 0.02-0.4 s where it runs; deep_modes 0: off.
    double deep_fit = -5;
    int deep_modes = 8;
    // Where the deep search runs on a window spanning 60 mm or more, this many seeds more from
    // the pair search: poses that put the window's two farthest contacts on surface points as
    // far apart, with normals at the same angles (docs/multitouch.md, "Pair search"; 8, on
    // train windows); 0: off.
    int pair_modes = 8;
    // > 0: the refinement also asks that the sensor's pad (free_space_w_mm x free_space_h_mm,
    // its window and a margin) be clear of the object this far behind the gel plane (the
    // sensor cannot pass through the object; docs/multitouch.md, "Free space"). 1.5 fitted on
    // train windows; 0: off.
    double free_space_mm = 1.5;
    double free_space_w_mm = 24, free_space_h_mm = 19;
    // Host threads an estimate climbs its modes on, and the object's lookup grid is built on:
    // 0, up to 4; n, at most n. Outputs do not depend on it.
    int threads = 0;
    double object_units = 1;     // multiply the object file's coordinates by this (glTF in metres: 1000)
    // The candidates protocol (the paper's S^c): hypotheses only at these contact points (in
    // the tracker's units, after object_units), n_spin each; empty: the whole surface. The
    // refinement turns and presses the gel at each candidate but never slides it off.
    std::vector<std::array<double, 3>> candidates;
    // Each step on the GPU (add_touch, a window's evaluation) runs node by node with GPU
    // timestamps, so step_nodes() says where its time went: slower (no overlap between the
    // nodes), the outputs the same bits.
    bool profile = false;
};

struct TrackerMode {
    std::array<double, 3> contact{};
    double probability = 0;
};

struct TrackerEstimate {
    int touches = 0;
    std::array<double, 3> contact{};         // Bayes contact of the current touch (min expected distance, on the surface)
    Motion pose;                             // the most likely pose of the current touch (refined over 6 DoF)
    std::array<double, 3> pose_contact{};    // where that pose's axis meets the surface
    std::vector<Motion> window_poses;        // every touch of the window, oldest first (the current one last)
    std::vector<TrackerMode> modes;          // best first, probabilities under the belief
    double mass_within_5mm = 0;              // the belief's own mass within 5 mm of `contact`
    double fit = 0;                          // `pose`'s geometry fit (log), as window_fit measures it
    // The window's gel shapes scored at `pose` and its window poses (log, times
    // render_refined_weight; with odometry noise, each earlier one aligned within it); 0: none.
    double pose_terms = 0;
    std::vector<float> heatmap;              // belief over the tracker's display_cloud(), in [0, 1]
    std::vector<float> sample_belief;        // the belief at each of sample_points(), sums to 1
};

// The online multi-touch filter: a belief over sensor poses on the object's
// surface. A mesh is sampled densely (the surface is exact to ~0.5 mm); a point
// cloud is used as it is (normals required; coarser: a pose is checked against
// the nearest cloud point's tangent plane). add_touch costs the same however
// many touches came before.
struct GelShape;  // below: the gel's shape from a frame

class Tracker {
public:
    Tracker(Context& context, const std::string& object_path, const TrackerOptions& options = {});
    Tracker(Context& context, const PointCloud& cloud, const TrackerOptions& options = {});
    ~Tracker();
    Tracker(Tracker&&) noexcept;
    Tracker& operator=(Tracker&&) noexcept;
    // A new tracker, no touches, on this one's object under other options, its surface not
    // read and built again (the build is most of a tracker's making): the estimates of a
    // Tracker made from the object with `options`, bit for bit. What shapes the surface
    // (n_spin, hypotheses, candidates, object_units) must be this tracker's: an Error names
    // the option that differs.
    Tracker with_options(const TrackerOptions& options) const;
    const TrackerOptions& options() const;  // as this tracker was made with them

    // The first touch takes no motion, every later one the motion from the
    // previous touch. network: that touch's TouchResult (its heat-map over
    // `object`'s cloud becomes a touch term); shape: its gel's shape (GelShapeReader
    // or load_indentation), scored by render-and-compare; null = geometry only.
    void add_touch(const std::optional<Motion>& motion, const TouchResult* network = nullptr,
                   const Object* object = nullptr, const GelShape* shape = nullptr);
    // add_touch with a precomputed touch_term() (empty: geometry only); shape: the touch's gel
    // shape for render-and-compare at the refined poses (render_refined_weight), or null.
    void add_touch_term(const std::optional<Motion>& motion, const std::vector<float>& term, const GelShape* shape = nullptr);
    // How far the sensor can move between two touches of this object (its bounding box's
    // diagonal, the presses, the odometry noise; the tracker's units): add_touch and the
    // windowed forms refuse a motion farther, naming its touch (1-based: the motion from touch
    // - 1), as a unit mismatch or a glitch. check_motion throws what they would, and nothing else.
    double max_hop() const;
    void check_motion(const Motion& motion, int touch) const;
    int touches() const;
    // Forgets every touch (a new grasp, the object moved); the object's tables stay.
    void reset();
    TrackerEstimate estimate() const;
    // The windowed form: motions between W touches (W - 1), optional results and shapes per touch.
    TrackerEstimate evaluate_window(const std::vector<Motion>& motions,
                                    const std::vector<const TouchResult*>& network = {}, const Object* object = nullptr,
                                    const std::vector<const GelShape*>& shapes = {});
    // Render-and-compare's log term of one gel shape over the hypotheses (belief() order).
    std::vector<float> shape_term(const GelShape& shape);
    // One touch's whole log term (the network's heat-map on `object` and/or render-and-compare of
    // its gel shape; empty: neither), to be reused: the windows of an evaluation share touches,
    // and evaluate_window_terms scores none of them again.
    std::vector<float> touch_term(const TouchResult* network, const Object* object, const GelShape* shape);
    // The windowed form over precomputed touch_term()s (one per touch; empty vectors: none),
    // and the touches' gel shapes for render-and-compare at the refined poses (empty, or one
    // per touch, null: none).
    TrackerEstimate evaluate_window_terms(const std::vector<Motion>& motions, const std::vector<std::vector<float>>& terms,
                                          const std::vector<const GelShape*>& shapes = {});
    // The geometry fit (log) of a pose of a window's last touch, refined from it as the
    // estimate's modes are. With the true pose known (evaluation), a fit above the
    // estimate's `fit` means the search missed the truth; at or below, a wrong pose
    // fits the geometry as well (ambiguity).
    double window_fit(const std::vector<Motion>& motions, const Motion& pose) const;
    std::vector<float> belief() const;        // over hypotheses, sums to 1
    std::vector<float> sample_points() const; // the hypotheses' surface samples, 3 floats each
    int n_spin() const;
    const PointCloud& display_cloud() const;  // the points heatmap values refer to
    // On the GPU now: the surface tables (one copy for a tracker and those with_options made
    // from it, each counting it), the step graphs' arenas, the codebook.
    uint64_t device_bytes() const;
    // In host memory: the surface and its tables, the registration's tree and the pair search's
    // index once a poorly fitting window made them, the dense points binned for render-and-compare
    // at the refined poses once a gel shape came, the display cloud (all shared with with_options').
    uint64_t host_bytes() const;
    double spacing_mm() const;                // the hypothesis samples' spacing
    // The last step's GPU time per node (name, ms), in run order, with options().profile
    // (empty without it); the estimate's refinement runs on the host and is not in it.
    std::vector<std::pair<std::string, double>> step_nodes() const;

    struct Impl;

private:
    friend struct TrackerAccess;  // engine/api internals (check_tracker)
    explicit Tracker(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

// The belief after each touch, side by side on the tracker's display cloud
// (one panel per estimate, captioned; the true contact marked where `truths` has one), so a
// person sees it converge.
void render_tracker_png(const std::string& path, const Tracker& tracker, const std::vector<TrackerEstimate>& steps,
                        const std::vector<std::string>& captions = {},
                        const std::vector<std::array<double, 3>>& truths = {});

// ---- The gel's shape from a frame (SPEC 9; docs/gel_shape.md) -------------

struct GelShapeOptions {
    std::string calibration;       // a Taxim-style calibration file; empty: the shipped GelSight one
    double mask_threshold = 0.7;   // the contact: 3x3 mean slope above this (fitted on the real presses)
    // The height's solve: red-black SOR sweeps on the frame's grid (`iterations`), from a coarse
    // start where levels > 0: the grid halved up to `levels` times, `coarse_iterations` sweeps
    // on each. From zeros (levels 0), 50 sweeps converge on a real press's small contact but not
    // on a wide one, which then needs the coarse start (rendered_frames() takes it).
    int iterations = 50;
    int levels = 0;
    int coarse_iterations = 30;
    // Undo a gain and offset per channel between the frame and the empty frame (LED drift,
    // exposure; our renderer's training frames vary both) before the calibration reads shading.
    bool match_lighting = true;
    // Host threads the reader's tables (the calibration inverted, once per reader: about half a
    // second on two cores) are built on: 0, up to 4; n, at most n. Reads do not depend on it.
    int threads = 0;
    // For frames rendered by `vtloc synth` (gentle presses of large objects, no optical halo): a
    // mask threshold of 0.05, chosen on renders of the procedural solids, and the solve from a
    // coarse start for their wide contacts (docs/gel_shape.md).
    static GelShapeOptions rendered_frames() {
        GelShapeOptions o;
        o.mask_threshold = 0.05;
        o.levels = 2, o.coarse_iterations = 30, o.iterations = 10;
        return o;
    }
};

struct GelShape {
    int height = 0, width = 0;     // the calibration's pixels
    double mm_per_px = 0;
    std::vector<float> depth_mm;   // the indentation, row-major; 0 outside the contact
    std::vector<float> grad_row, grad_col;  // the indentation's gradient (mm per mm)
    std::vector<uint8_t> mask;     // the contact, 0/1
};

// Reads the gel's shape from frames on the GPU: the colour change against the
// sensor's empty frame inverted through the calibration into gradients, a
// contact mask, and the height inside it. A frame larger than the calibration
// with the same aspect is resampled to it (real frames: 240x320, 480x640);
// another aspect or a smaller frame is an error. A reader holds the calibration's
// tables (25 MB) on the device only, none on the host.
class GelShapeReader {
public:
    explicit GelShapeReader(Context& context, const GelShapeOptions& options = {});
    ~GelShapeReader();
    GelShapeReader(GelShapeReader&&) noexcept;
    GelShapeReader& operator=(GelShapeReader&&) noexcept;
    // empty: the sensor's frame with nothing pressed; null: the calibration's own. A frame's
    // errors begin with its name (give its file's path where it came from one).
    GelShape read(const TactileImage& frame, const TactileImage* empty = nullptr, const std::string& frame_name = "frame",
                  const std::string& empty_name = "empty frame");
    // Throws what read() would for these frames (decoded size, aspect, a black or saturated
    // frame), without the GPU: a caller checks a whole sequence before reading any.
    void check_frame(const TactileImage& frame, const TactileImage* empty = nullptr, const std::string& frame_name = "frame",
                     const std::string& empty_name = "empty frame") const;
    int height() const;
    int width() const;

private:
    friend struct GelShapeAccess;  // engine/api internals (check_tracker)
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A gel indentation as a 16-bit PNG in micrometres (vtloc synth --indentation's
// touches/<id>.depth.png, vtloc shape's height.png) at mm_per_px: the contact is
// where it is above zero. Throws naming the file for another pixel type.
GelShape load_indentation(const std::string& path, double mm_per_px);

// Writes DIR/height.png (16-bit grey, micrometres, like vtloc synth --indentation), DIR/shape.ply
// (the contact's points: x, y in mm from the frame's top-left, z the indentation) and
// DIR/shape.png (frame | slope | height | mask). Returns the three paths.
std::vector<std::string> write_gel_shape(const std::string& dir, const GelShape& shape, const TactileImage& frame);

// ---- Outputs ----------------------------------------------------------------

// PLY point cloud of the object with `contact_prob` and an RGB colour per point
// (MeshLab, CloudCompare, Open3D show it). heat: one value per cloud point.
void write_heatmap_ply(const std::string& path, const Object& object, const std::vector<float>& heat);

struct RenderOptions {
    int width = 1280, height = 720;          // at least 640 x 400
    std::optional<std::array<double, 3>> contact;       // predicted, object units
    std::optional<std::array<double, 3>> ground_truth;  // object units
    std::array<float, 3> up{0, 1, 0};        // object axis drawn upwards (glTF: +y)
    std::string caption;
    const TactileImage* tactile = nullptr;   // shown beside the views
    int display_points = 30000;              // denser sample of a mesh for the picture
};

// PNG picture of a heat-map over the object, from two sides. A mesh object is
// drawn from a denser sample of its surface, each sample taking the heat of
// its nearest cloud point.
void render_heatmap_png(const std::string& path, const Object& object, const std::vector<float>& heat,
                        const RenderOptions& options = {});

// Every tensor of a result (keep_tensors) as one safetensors file, comparable
// name by name with `python3 -m weights_tools.golden`.
void save_tensors(const std::string& path, const std::vector<Tensor>& tensors, const std::string& config_json = "");

}  // namespace vtloc::api
