// The tactile image path: a PNG, JPEG or BMP file decoded (engine/io/image_codec.cpp),
// then the model's input tensor; also the 16-bit depth-image path.
#include "base/error.h"
#include "engine/io/image.h"
#include "engine/model/tactile_encoder.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    const bool depth = data[0] & 1;
    const std::string path = vtloc::fuzz::write_input(data + 1, size - 1, ".png");
    try {
        if (depth) {
            vtloc::io::load_depth_image(path);
        } else {
            const vtloc::io::RgbImage im = vtloc::io::load_tactile_image(path);
            vtloc::tactile_image_input(im.pixels.data(), im.pixels.size(), im.height, im.width);
        }
    } catch (const vtloc::Error&) {
    }
    return 0;
}
