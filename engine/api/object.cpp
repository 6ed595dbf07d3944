// Inputs of the public API: point clouds, candidates, tactile images, and
// encoding an object with a model's point branch.
#include <cmath>

#include "engine/api/api_internal.h"
#include "engine/io/candidates.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "engine/io/depth.h"
#include "engine/model/cloud_reduce.h"
#include "engine/model/normals.h"

namespace vtloc::api {

PointCloud to_point_cloud(const HostTensor& t) {
    PointCloud c;
    const size_t n = size_t(t.shape[0]), w = size_t(t.shape[1]);
    c.xyz.resize(n * 3);
    if (w == 6) c.normals.resize(n * 3);
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < 3; ++k) {
            c.xyz[i * 3 + k] = t.data[i * w + k];
            if (w == 6) c.normals[i * 3 + k] = t.data[i * 6 + 3 + k];
        }
    return c;
}

HostTensor cloud_tensor(const PointCloud& cloud) {
    const size_t n = cloud.size();
    if (cloud.xyz.size() % 3 != 0) throw Error("the object cloud: xyz needs 3 floats per point");
    const bool has_normals = !cloud.normals.empty();
    if (has_normals && cloud.normals.size() != cloud.xyz.size())
        throw Error("the object cloud has " + std::to_string(n) + " points but " +
                    std::to_string(cloud.normals.size() / 3) + " normals");
    const size_t w = has_normals ? 6 : 3;
    HostTensor t({int64_t(n), int64_t(w)});
    for (size_t i = 0; i < n; ++i)
        for (size_t k = 0; k < 3; ++k) {
            t.data[i * w + k] = cloud.xyz[i * 3 + k];
            if (has_normals) t.data[i * 6 + 3 + k] = cloud.normals[i * 3 + k];
        }
    return t;
}

namespace {

std::string where(const std::string& source) { return source.empty() ? "the object" : source; }

// What a cloud goes through before the point branch, on the model's GPU for
// Backend::Gpu (else the CPU reference): a large one (kReduceFromPoints) is
// voxel-reduced to ~4 x sample_points; one without normals (N x 3) gets
// estimated ones, oriented towards `viewpoint` when given; a reduced one is
// then cut to sample_points by FPS. Fills the Object's provenance fields.
HostTensor prepare_cloud(const Model::Impl& m, HostTensor cloud, Backend b, const std::string& source,
                         const std::optional<std::array<double, 3>>& viewpoint, Object::Impl& o) {
    rt::Context* ctx = b == Backend::Gpu ? m.gpu : nullptr;
    try {
        o.source_points = size_t(cloud.shape[0]);
        const bool large = cloud.shape[0] >= kReduceFromPoints;
        if (large) cloud = voxel_reduce(cloud, 4 * m.info.sample_points);
        o.normals_estimated = cloud.shape[1] == 3;
        if (o.normals_estimated) {
            NormalOptions n;
            n.towards = viewpoint;
            cloud = estimate_normals(ctx, cloud, n);
        }
        if (large) cloud = reduce_cloud(ctx, cloud, m.info.sample_points);
        return cloud;
    } catch (const std::exception& e) {
        throw Error(where(source) + ": " + one_line(e.what()));
    }
}

Object::Impl make_object(Object::Impl o, const std::string& source, HostTensor cloud, const HostTensor* candidates) {
    o.source = source;
    // `cloud` is checked where it came in (load_object, encode_object) and its normals are unit
    o.raw_cloud = std::move(cloud);
    o.cloud = to_point_cloud(o.raw_cloud);
    if (candidates) {
        o.candidates = candidates->data;
    } else {
        o.candidates = o.cloud.xyz;
        o.own_candidates = true;
    }
    return o;
}

HostTensor candidate_tensor(const std::vector<float>& c, const std::string& what) {
    if (c.size() % 3 != 0) throw Error(what + ": candidates need 3 floats each, got " + std::to_string(c.size()));
    for (size_t i = 0; i < c.size(); ++i)
        if (!std::isfinite(c[i])) throw Error(what + ": candidate " + std::to_string(i / 3) + " holds NaN or inf");
    return HostTensor({int64_t(c.size() / 3), 3}, c);
}

}  // namespace

PointCloud load_point_cloud(const std::string& path, int64_t n_points, uint64_t seed) {
    return guarded([&] {
        if (n_points < 1) throw Error("load_point_cloud: n_points must be >= 1");
        return to_point_cloud(io::load_object(path, n_points, seed));  // checked; xyz only without normals
    });
}

PointCloud load_depth_cloud(const std::string& depth_path, const std::array<double, 4>& intrinsics,
                            const std::string& mask_path, double unit_mm) {
    return guarded([&] {
        const io::CameraIntrinsics k{intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3]};
        PointCloud c;
        c.xyz = io::depth_to_cloud(depth_path, k, mask_path, unit_mm).data;
        c.viewpoint = std::array<double, 3>{0, 0, 0};  // the camera
        return c;
    });
}

std::vector<float> load_candidates(const std::string& path) {
    return guarded([&] { return io::load_candidates(path).data; });
}

TactileImage load_tactile_image(const std::string& path) {
    return guarded([&] {
        io::RgbImage im = io::load_tactile_image(path);
        return TactileImage{im.height, im.width, std::move(im.pixels)};
    });
}

namespace {

std::shared_ptr<const Object::Impl> encode(Model::Impl& m, Object::Impl o, Backend backend) {
    io::require_points(o.raw_cloud, m.info.min_points, where(o.source));
    if (!o.own_candidates && o.candidates.empty())
        throw Error(where(o.source) + ": the candidate set is empty");
    HostTensor cand = candidate_tensor(o.candidates, where(o.source));
    std::lock_guard<std::mutex> lock(m.mu);
    o.encoded = m.runner(backend).encode_object(o.raw_cloud, o.own_candidates ? nullptr : &cand);
    o.model_key = m.key;
    return std::make_shared<const Object::Impl>(std::move(o));
}

}  // namespace

Object Model::encode_object(const std::string& object_path, const std::string& candidates_path, Backend backend) {
    return guarded([&] {
        Object::Impl o;
        HostTensor cloud = prepare_cloud(*impl_, io::load_object(object_path, impl_->info.sample_points), backend,
                                         object_path, std::nullopt, o);
        HostTensor cand;
        if (!candidates_path.empty()) cand = io::load_candidates(candidates_path);
        o = make_object(std::move(o), object_path, std::move(cloud), candidates_path.empty() ? nullptr : &cand);
        Object out;
        out.impl_ = encode(*impl_, std::move(o), backend);
        return out;
    });
}

Object Model::encode_object(const PointCloud& cloud, const std::vector<float>& candidates, Backend backend) {
    return guarded([&] {
        HostTensor t = cloud_tensor(cloud);
        if (cloud.size() == 0) throw Error("the object cloud is empty");
        io::check_cloud(t, "the object cloud");
        Object::Impl o;
        t = prepare_cloud(*impl_, std::move(t), backend, "", cloud.viewpoint, o);
        HostTensor cand;
        if (!candidates.empty()) cand = candidate_tensor(candidates, "the candidates");
        o = make_object(std::move(o), "", std::move(t), candidates.empty() ? nullptr : &cand);
        Object out;
        out.impl_ = encode(*impl_, std::move(o), backend);
        return out;
    });
}

Object::Object() = default;
Object::~Object() = default;
Object::Object(const Object&) = default;
Object& Object::operator=(const Object&) = default;

namespace {
const Object::Impl& need(const std::shared_ptr<const Object::Impl>& p) {
    if (!p) throw Error("empty Object (make one with Model::encode_object)");
    return *p;
}
}  // namespace

const std::string& Object::source() const { return guarded([&]() -> const std::string& { return need(impl_).source; }); }
const PointCloud& Object::cloud() const { return guarded([&]() -> const PointCloud& { return need(impl_).cloud; }); }
const std::vector<float>& Object::candidates() const {
    return guarded([&]() -> const std::vector<float>& { return need(impl_).candidates; });
}
size_t Object::candidate_count() const { return candidates().size() / 3; }
bool Object::normals_estimated() const { return guarded([&] { return need(impl_).normals_estimated; }); }
size_t Object::source_points() const { return guarded([&] { return need(impl_).source_points; }); }
std::array<double, 3> Object::centre() const { return guarded([&] { return need(impl_).encoded.frame.centre; }); }
double Object::scale() const { return guarded([&] { return need(impl_).encoded.frame.scale; }); }

}  // namespace vtloc::api
