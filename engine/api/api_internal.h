#pragma once
#include <mutex>
// What the public API's pimpl classes hold, and the one place where engine
// exceptions become vtloc::api::Error. Private to engine/api/*.cpp.
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "engine/api/vtloc/vtloc.h"
#include "engine/check/graph_check.h"
#include "engine/model/model_file.h"
#include "engine/model/vtloc_runner.h"
#include "runtime/context.h"

namespace vtloc::track {
class Tracker;
class CodebookScorer;
struct Codebook;
}

namespace vtloc::api {

// The filter inside an api::Tracker (engine/api/tracker.cpp; check_tracker drives it).
struct TrackerAccess {
    static track::Tracker& core(Tracker& t);
    // Render-and-compare's scorer on the device, as the tracker makes its own, and on the ops'
    // CPU references, both over the codebook the tracker reads (its cache, or rendered on the
    // device); and one gel shape's term
    // through either as shape_term() scores it (check_tracker --shapes).
    struct ShapeScorers {
        std::shared_ptr<const track::Codebook> book;  // codebook_cache's, or the device's render
        std::shared_ptr<track::CodebookScorer> gpu, cpu;
    };
    static ShapeScorers shape_scorers(Tracker& t);
    static std::vector<float> shape_term(Tracker& t, track::CodebookScorer& scorer, const GelShape& g);
};

// The reader inside an api::GelShapeReader (engine/api/gel_shape.cpp; check_tracker --shapes).
struct GelShapeAccess {
    // The reader's graph checked node by node against the CPU references (check::check_graph) on
    // the inputs read() gives it for a frame and empty frame (null: the calibration's), the shape
    // read() returns for them (the reader's own executor), and the shape its full CPU reference run
    // gives (what read() should return). The frame is prepared once for all three.
    struct Checked {
        check::GraphCheck graph;
        GelShape read, reference;
    };
    // One keep-all executor of the reader's graph for every frame checked (made at the first:
    // its tables built, uploaded and its memory planned once a tour, not once a frame).
    class Checker {
    public:
        Checker(GelShapeReader& r, rt::Context& ctx);
        ~Checker();
        Checked check(const TactileImage& frame, const TactileImage* empty, const std::string& frame_name,
                      const std::string& empty_name);

    private:
        GelShapeReader& reader_;
        rt::Context& ctx_;
        std::unique_ptr<WeightStore> weights_;  // the reader's tables, built again (it keeps none on the host)
        std::unique_ptr<GpuExecutor> exec_;
    };
};

// TEST-ONLY: the context's next submit fails with VK_ERROR_DEVICE_LOST, as a
// driver reset would (the tests include this internal header; users cannot).
namespace testing {
void simulate_device_loss(Context& c);
}  // namespace testing

struct Context::Impl {
    rt::Context ctx;
    DeviceInfo device;
    explicit Impl(const rt::ContextOptions& o) : ctx(o) {}
};

struct ContextAccess {
    static rt::Context& rt(Context& c) { return c.impl_->ctx; }
};

struct Object::Impl {
    std::string source;
    std::string model_key;  // Model::Impl::key of the model that encoded it
    PointCloud cloud;
    std::vector<float> candidates;
    bool own_candidates = false;  // candidates are the cloud's points
    bool normals_estimated = false;  // the input had none (normal_estimate made them)
    size_t source_points = 0;        // points in the input, before a large cloud's reduction
    HostTensor raw_cloud;         // [N, 6] object units, checked
    EncodedObject encoded;
};

struct Model::Impl {
    ModelInfo info;
    std::string key;                      // identifies the weights an Object was encoded with
    rt::Context* gpu = nullptr;           // null: CPU-only model
    std::unique_ptr<VtlocRunner> gpu_runner, cpu_runner;
    // A Model may be shared between threads: its runners (cached graphs, last
    // timings) serve one call at a time.
    std::mutex mu;

    VtlocRunner& runner(Backend b);
};

// Loads a weight file and checks it fully (config schema, every tensor the
// network needs); `info` is filled from it.
ModelFile load_checked_model(const std::string& path, ModelInfo& info);

// The one conversion between the API's PointCloud and the engine's [N, 6]
// (or [N, 3] when the cloud has no normals) tensor; object.cpp.
HostTensor cloud_tensor(const PointCloud& cloud);
PointCloud to_point_cloud(const HostTensor& t);

DeviceInfo to_api(const rt::DeviceInfo& d);

// Throws Error("<what> must be a finite number > 0, got <v>") unless it is.
void check_mm_per_px(double v, const std::string& what);
// rescale_tactile_image without the exception guard (engine/api/rescale.cpp).
TactileImage rescale_frame(const TactileImage& image, double image_mm, double model_mm);

// Collapses a message to one line (multi-line engine messages, e.g. device lists).
std::string one_line(std::string s);

// Runs f, turning every exception into vtloc::api::Error.
template <class F>
auto guarded(F&& f) -> decltype(f()) {
    try {
        return f();
    } catch (const Error&) {
        throw;
    } catch (const std::bad_alloc&) {
        throw Error("out of memory");
    } catch (const std::exception& e) {
        throw Error(one_line(e.what()));
    } catch (...) {
        throw Error("unknown internal error");
    }
}

}  // namespace vtloc::api
