// Reading the GelSight calibration (data/gelsight/README.md) with every
// tensor's dtype, shape and values checked, so the renderer can index it
// without further checks.
#include "engine/sensor/calibration.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "base/error.h"
#include "engine/safetensors.h"

#ifndef VTLOC_SOURCE_DIR
#define VTLOC_SOURCE_DIR ""
#endif

namespace vtloc::sensor {

namespace {

constexpr const char* kCalibFile = "objectfolder_gelsight_calib.safetensors";

[[noreturn]] void fail(const SafetensorsFile& f, const std::string& tensor, const std::string& what) {
    throw Error(f.source() + ": tensor '" + tensor + "' " + what);
}

const TensorInfo& tensor(const SafetensorsFile& f, const std::string& name, const Shape& shape) {
    const TensorInfo* t = f.find(name);
    if (!t) fail(f, name, "is missing");
    if (t->shape != shape) fail(f, name, "has shape " + shape_str(t->shape) + ", expected " + shape_str(shape));
    return *t;
}

std::vector<float> floats(const SafetensorsFile& f, const std::string& name, const Shape& shape) {
    const TensorInfo& t = tensor(f, name, shape);
    if (t.dtype != DType::F32 && t.dtype != DType::F16 && t.dtype != DType::BF16)
        fail(f, name, std::string("has dtype ") + dtype_name(t.dtype) + ", expected F32");
    std::vector<float> v = f.to_f32(t);
    for (size_t i = 0; i < v.size(); ++i)
        if (!std::isfinite(v[i])) fail(f, name, "has a non-finite value at element " + std::to_string(i));
    return v;
}

std::vector<uint8_t> bytes_u8(const SafetensorsFile& f, const std::string& name, const Shape& shape) {
    const TensorInfo& t = tensor(f, name, shape);
    if (t.dtype != DType::U8) fail(f, name, std::string("has dtype ") + dtype_name(t.dtype) + ", expected U8");
    auto b = f.bytes(t);
    return {b.begin(), b.end()};
}

Calibration from_file(const SafetensorsFile& f);


}  // namespace

Calibration load_calibration(const std::string& path) {
    return from_file(SafetensorsFile::load(path, "calibration file"));
}

Calibration parse_calibration(std::vector<uint8_t> bytes, const std::string& source) {
    return from_file(SafetensorsFile::parse(std::move(bytes), source, "calibration file"));
}

namespace {

Calibration from_file(const SafetensorsFile& f) {
    Calibration c;
    const TensorInfo* bg = f.find("real_bg");
    if (!bg) fail(f, "real_bg", "is missing");
    if (bg->shape.size() != 3 || bg->shape[2] != 3 || bg->shape[0] < 8 || bg->shape[1] < 8 || bg->shape[0] > 4096 ||
        bg->shape[1] > 4096)
        fail(f, "real_bg", "has shape " + shape_str(bg->shape) + ", expected HxWx3 (8..4096 pixels a side)");
    c.height = int(bg->shape[0]);
    c.width = int(bg->shape[1]);
    const int64_t H = c.height, W = c.width;

    const TensorInfo* pr = f.find("poly_r");
    if (!pr) fail(f, "poly_r", "is missing");
    if (pr->shape.size() != 3 || pr->shape[0] != pr->shape[1] || pr->shape[2] != 6 || pr->shape[0] < 2 ||
        pr->shape[0] > 4096)
        fail(f, "poly_r", "has shape " + shape_str(pr->shape) + ", expected BxBx6");
    c.bins = int(pr->shape[0]);
    const char* poly_names[3] = {"poly_r", "poly_g", "poly_b"};
    for (int ch = 0; ch < 3; ++ch) c.poly[ch] = floats(f, poly_names[ch], {c.bins, c.bins, 6});
    c.real_bg = floats(f, "real_bg", {H, W, 3});
    c.depth_bg = floats(f, "depth_bg", {H, W});

    // The press frames are optional as a set (a user's own sensor), all or none.
    if (f.find("press_imgs")) {
        const TensorInfo& pi = f.at("press_imgs");
        if (pi.shape.size() != 4 || pi.shape[0] < 1 || pi.shape[0] > 100000)
            fail(f, "press_imgs", "has shape " + shape_str(pi.shape) + ", expected Nx" + std::to_string(H) + "x" +
                                      std::to_string(W) + "x3");
        c.n_press = int(pi.shape[0]);
        const int64_t N = c.n_press;
        c.press_imgs = bytes_u8(f, "press_imgs", {N, H, W, 3});
        c.press_f0 = bytes_u8(f, "press_f0", {H, W, 3});
        c.press_center = floats(f, "press_center", {N, 2});
        const TensorInfo& rad = tensor(f, "press_radius", {N});
        if (rad.dtype != DType::I32 && rad.dtype != DType::I64 && rad.dtype != DType::I16 && rad.dtype != DType::U8)
            fail(f, "press_radius", std::string("has dtype ") + dtype_name(rad.dtype) + ", expected I32");
        c.press_radius = f.to_i32(rad);
        for (int i = 0; i < c.n_press; ++i)
            if (c.press_radius[i] <= 0) fail(f, "press_radius", "has a non-positive radius at element " + std::to_string(i));
    }
    if (auto it = f.metadata().find("sensor"); it != f.metadata().end()) {
        // "pixmm=0.1245" in the shipped file's metadata; the default otherwise.
        auto p = it->second.find("pixmm=");
        if (p != std::string::npos) {
            double v = std::strtod(it->second.c_str() + p + 6, nullptr);
            if (std::isfinite(v) && v > 0) c.mm_per_px = v;
        }
    }
    return c;
}

}  // namespace

std::string default_calibration_path() {
    namespace fs = std::filesystem;
    std::error_code ec;
    std::vector<fs::path> tried;
    if (const char* env = std::getenv("VTLOC_GELSIGHT_CALIB"); env && *env) {
        if (fs::is_regular_file(env, ec)) return env;
        throw Error(std::string("VTLOC_GELSIGHT_CALIB=") + env + ": no such file");
    }
    if (*VTLOC_SOURCE_DIR) tried.push_back(fs::path(VTLOC_SOURCE_DIR) / "data/gelsight" / kCalibFile);
    fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec) tried.push_back(exe.parent_path().parent_path() / "share/vtloc/data/gelsight" / kCalibFile);
    std::string list;
    for (const fs::path& p : tried) {
        if (fs::is_regular_file(p, ec)) return p.string();
        list += (list.empty() ? "" : ", ") + p.string();
    }
    throw Error("cannot find the GelSight calibration (tried " + list + "); set VTLOC_GELSIGHT_CALIB");
}

}  // namespace vtloc::sensor
