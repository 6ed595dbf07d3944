// The render-and-compare cache reader (engine/track/codebook.h) on arbitrary
// bytes: every input either loads as this surface's codebook (finite heights of
// the right count) or throws vtloc::Error naming the problem.
#include <cmath>
#include <cstdlib>
#include <vector>

#include "base/error.h"
#include "engine/safetensors.h"
#include "engine/track/codebook.h"

namespace {

// Two samples on the plane z = 0 looking down, one spin: the seed corpus's codebook
// (tests/fuzz/make_corpus.py) was written for exactly these.
const vtloc::track::Surface& surface() {
    static const vtloc::track::Surface s = [] {
        vtloc::track::Surface r;
        r.samples = {0, 0, 0, 0, 0, 1, 1, 0, 0, 3, 0, 0, 0, 0, 1, 1, 0, 0};
        r.dense = {0, 0, 0, 0, 0, 1};
        r.spins = {1, 0};
        r.from_mesh = true;
        return r;
    }();
    return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    try {
        const vtloc::SafetensorsFile f = vtloc::SafetensorsFile::parse(std::vector<uint8_t>(data, data + size), "/fuzz");
        const vtloc::track::Codebook b = vtloc::track::parse_codebook(f, "/fuzz", surface());
        if (b.heights.size() != size_t(2 * b.G * b.G)) std::abort();  // the reader promised this surface's maps
        for (float v : b.heights)
            if (!std::isfinite(v)) std::abort();
    } catch (const vtloc::Error&) {
    }
    return 0;
}
