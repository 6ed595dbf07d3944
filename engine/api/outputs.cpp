// Outputs of the public API: heat-map PLY, PNG render, tensor dumps.
#include <cstring>

#include "engine/api/api_internal.h"
#include "engine/api/display_sample.h"
#include "engine/io/file_bytes.h"
#include "engine/io/heatmap_ply.h"
#include "engine/io/image.h"
#include "engine/io/object.h"
#include "engine/io/render.h"
#include "engine/safetensors.h"

namespace vtloc::api {

namespace {

void check_heat(const Object& object, const std::vector<float>& heat) {
    if (heat.size() != object.cloud().size())
        throw Error("the heat-map has " + std::to_string(heat.size()) + " values for an object of " +
                    std::to_string(object.cloud().size()) + " points");
}

std::array<float, 3> to_float(const std::array<double, 3>& p) { return {float(p[0]), float(p[1]), float(p[2])}; }

}  // namespace

void write_heatmap_ply(const std::string& path, const Object& object, const std::vector<float>& heat) {
    guarded([&] {
        check_heat(object, heat);
        io::write_heatmap_ply(path, cloud_tensor(object.cloud()), heat);
    });
}

void render_heatmap_png(const std::string& path, const Object& object, const std::vector<float>& heat,
                        const RenderOptions& options) {
    guarded([&] {
        check_heat(object, heat);
        HostTensor cloud = cloud_tensor(object.cloud());
        // A mesh reads far better from a dense, even sample of its surface than
        // from the model's ~1k points; each sample shows its nearest point's heat.
        HostTensor display = cloud;
        std::vector<float> display_heat = heat;
        const std::string ext = io::extension_of(object.source());
        if ((ext == "glb" || ext == "gltf") && options.display_points > int64_t(cloud.shape[0])) {
            display = display_sample(io::load_gltf_mesh(object.source()), options.display_points, object.source());
            display_heat = io::nearest_heat(cloud, heat, display);
        }
        io::RenderOptions ro;
        ro.width = options.width;
        ro.height = options.height;
        if (options.contact) ro.contact = to_float(*options.contact);
        if (options.ground_truth) ro.ground_truth = to_float(*options.ground_truth);
        ro.up = options.up;
        ro.caption = options.caption;
        io::RgbImage tactile;
        if (options.tactile) {
            tactile = io::RgbImage(options.tactile->height, options.tactile->width);
            if (options.tactile->rgb.size() != tactile.pixels.size())
                throw Error("RenderOptions::tactile: the image's size does not match its pixels");
            if (!tactile.pixels.empty())
                std::memcpy(tactile.pixels.data(), options.tactile->rgb.data(), tactile.pixels.size());
            ro.tactile = &tactile;
        }
        io::save_png(path, io::render_heatmap(display, display_heat, ro));
    });
}

void save_tensors(const std::string& path, const std::vector<Tensor>& tensors, const std::string& config_json) {
    guarded([&] {
        std::vector<TensorBlob> blobs;
        for (const Tensor& t : tensors) {
            const size_t n = size_t(numel(t.shape));
            if (!t.u8.empty()) {
                if (t.u8.size() != n) throw Error("tensor '" + t.name + "': data does not match its shape");
                blobs.push_back({t.name, DType::U8, t.shape, t.u8});
            } else if (!t.i32.empty()) {
                if (t.i32.size() != n) throw Error("tensor '" + t.name + "': data does not match its shape");
                blobs.push_back(TensorBlob::i32(t.name, t.shape, t.i32));
            } else {
                if (t.f32.size() != n) throw Error("tensor '" + t.name + "': data does not match its shape");
                blobs.push_back(TensorBlob::f32(t.name, t.shape, t.f32));
            }
        }
        std::map<std::string, std::string> meta{{"format", "pt"}, {"vtloc.dump", std::string("vtloc ") + version()}};
        if (!config_json.empty()) meta["vtloc.config"] = nlohmann::json::parse(config_json).dump();
        write_safetensors(path, blobs, meta);
    });
}

}  // namespace vtloc::api
