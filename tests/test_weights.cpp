// The safetensors reader and the weight store: a good file round-trips, and
// each malformed file gives its own error naming the tensor or field.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "base/error.h"
#include "engine/safetensors.h"
#include "engine/weights.h"
#include "tests/harness.h"

using namespace vtloc;

namespace {

const char* kConfig = R"("__metadata__": {"vtloc.config": "{\"name\": \"t\"}"})";

// A file with this JSON header and `data_bytes` bytes of data; header length
// field overridable to fake truncation.
std::vector<uint8_t> raw_file(const std::string& header, size_t data_bytes, int64_t len_override = -1) {
    uint64_t len = len_override >= 0 ? uint64_t(len_override) : header.size();
    // Sized up front: inserting after an 8-byte vector trips a GCC 12 -Warray-bounds false positive.
    std::vector<uint8_t> b(8 + header.size());
    std::memcpy(b.data(), &len, 8);
    std::copy(header.begin(), header.end(), b.begin() + 8);
    for (size_t i = 0; i < data_bytes; ++i) b.push_back(uint8_t(i));
    return b;
}

std::string header_with(const std::string& tensors, const std::string& meta = kConfig) {
    return "{" + meta + (tensors.empty() ? "" : ", " + tensors) + "}";
}

void expect_weights_error(const std::vector<uint8_t>& bytes, const std::string& fragment) {
    INFO("expected an error containing: " << fragment);
    REQUIRE_THROWS_WITH(WeightStore::from_file(SafetensorsFile::parse(bytes, "bad.safetensors")),
                        Catch::Contains(fragment) && Catch::Contains("bad.safetensors"));
}

}  // namespace

TEST_CASE("safetensors round trip", "[weights]") {
    std::string path = test::temp_path("roundtrip.safetensors");
    std::vector<float> a{1.f, -2.5f, 3.25f, 0.f, 1e-20f, -7.f};
    write_safetensors(path,
                      {TensorBlob::f32("b.weight", {2, 3}, a), TensorBlob::i32("idx", {2}, {7, -9}),
                       TensorBlob::f32("empty", {0, 4}, {})},
                      {{"vtloc.config", R"({"name": "rt", "C": 16})"}, {"note", "x"}});
    SafetensorsFile f = SafetensorsFile::load(path);
    REQUIRE(f.tensors().size() == 3);
    CHECK(f.to_f32(f.at("b.weight")) == a);
    CHECK(f.to_i32(f.at("idx")) == std::vector<int32_t>{7, -9});
    CHECK(f.metadata().at("note") == "x");
    REQUIRE_THROWS_WITH(f.at("missing"), Catch::Contains("no tensor named 'missing'"));

    // The I32 tensor is not a weight: the store refuses it by name.
    REQUIRE_THROWS_WITH(WeightStore::from_file(f), Catch::Contains("'idx' has dtype I32"));
}

TEST_CASE("weight store widens F16 and ignores I64", "[weights]") {
    // F16: 1.0, -2.0, 0.5, smallest subnormal, +inf
    const uint16_t half[] = {0x3C00, 0xC000, 0x3800, 0x0001, 0x7C00};
    std::string h = header_with(R"("h": {"dtype": "F16", "shape": [5], "data_offsets": [0, 10]},
        "n": {"dtype": "I64", "shape": [1], "data_offsets": [10, 18]})");
    auto bytes = raw_file(h, 18);
    std::memcpy(bytes.data() + 8 + h.size(), half, 10);
    WeightStore w = WeightStore::from_file(SafetensorsFile::parse(bytes, "f16"));
    CHECK_FALSE(w.has("n"));
    const HostTensor& t = w.get("h", {5});
    CHECK(t.data[0] == 1.0f);
    CHECK(t.data[1] == -2.0f);
    CHECK(t.data[2] == 0.5f);
    CHECK(t.data[3] == std::ldexp(1.0f, -24));
    CHECK(std::isinf(t.data[4]));
    CHECK(w.config()["name"] == "t");
    CHECK(w.parameter_count() == 5);
}

TEST_CASE("malformed weight files each give their own error", "[weights]") {
    const std::string ok = R"("a": {"dtype": "F32", "shape": [2, 3], "data_offsets": [0, 24]})";
    // The well-formed base case loads.
    REQUIRE_NOTHROW(WeightStore::from_file(SafetensorsFile::parse(raw_file(header_with(ok), 24), "good")));

    SECTION("shorter than the length field") {
        REQUIRE_THROWS_WITH(SafetensorsFile::parse({1, 2, 3}, "bad.safetensors"), Catch::Contains("too short"));
    }
    SECTION("truncated header") {
        auto b = raw_file(header_with(ok), 24);
        b.resize(20);
        expect_weights_error(b, "runs past the end of the file");
    }
    SECTION("header length past EOF") {
        expect_weights_error(raw_file(header_with(ok), 24, 5000), "runs past the end of the file");
    }
    SECTION("header length over 100 MB") {
        expect_weights_error(raw_file(header_with(ok), 24, 200'000'000), "exceeds the 100 MB limit");
    }
    SECTION("bad JSON") { expect_weights_error(raw_file("{\"a\": [1, 2", 0), "not valid JSON"); }
    SECTION("header not an object") { expect_weights_error(raw_file("[1, 2]", 0), "not a JSON object"); }
    SECTION("unknown dtype") {
        expect_weights_error(
            raw_file(header_with(R"("a": {"dtype": "Q7", "shape": [2], "data_offsets": [0, 2]})"), 2),
            "tensor 'a': unknown dtype 'Q7'");
    }
    SECTION("shape and span disagree") {
        expect_weights_error(
            raw_file(header_with(R"("a": {"dtype": "F32", "shape": [2, 3], "data_offsets": [0, 20]})"), 20),
            "tensor 'a': shape [2, 3] of F32 needs 24 bytes but data_offsets span 20");
    }
    SECTION("overlapping spans") {
        expect_weights_error(raw_file(header_with(R"("a": {"dtype": "F32", "shape": [2], "data_offsets": [0, 8]},
            "b": {"dtype": "F32", "shape": [2], "data_offsets": [4, 12]})"), 12),
                             "tensors 'a' and 'b' overlap");
    }
    SECTION("gap between spans") {
        expect_weights_error(raw_file(header_with(R"("a": {"dtype": "F32", "shape": [1], "data_offsets": [0, 4]},
            "b": {"dtype": "F32", "shape": [1], "data_offsets": [8, 12]})"), 12),
                             "gap of 4 bytes before tensor 'b'");
    }
    SECTION("span past EOF") {
        expect_weights_error(raw_file(header_with(ok), 16), "tensor 'a': data_offsets [0, 24] run past the end");
    }
    SECTION("bytes not covered by any tensor") {
        expect_weights_error(raw_file(header_with(ok), 32), "8 bytes after the last tensor are not covered");
    }
    SECTION("missing config") {
        expect_weights_error(raw_file(header_with(ok, R"("__metadata__": {"format": "pt"})"), 24),
                             "missing __metadata__[\"vtloc.config\"]");
    }
    SECTION("config is not JSON") {
        expect_weights_error(raw_file(header_with(ok, R"("__metadata__": {"vtloc.config": "{oops"})"), 24),
                             "__metadata__[\"vtloc.config\"] is not valid JSON");
    }
    SECTION("metadata value not a string") {
        expect_weights_error(raw_file(header_with(ok, R"("__metadata__": {"vtloc.config": 5})"), 24),
                             "__metadata__[\"vtloc.config\"] is not a string");
    }
    SECTION("missing data_offsets") {
        expect_weights_error(raw_file(header_with(R"("a": {"dtype": "F32", "shape": [1]})"), 4),
                             "tensor 'a': data_offsets must be");
    }
    SECTION("negative dimension") {
        expect_weights_error(
            raw_file(header_with(R"("a": {"dtype": "F32", "shape": [-1], "data_offsets": [0, 4]})"), 4),
            "tensor 'a': shape entries must be non-negative");
    }
    SECTION("integer weights") {
        expect_weights_error(
            raw_file(header_with(R"("a": {"dtype": "I32", "shape": [1], "data_offsets": [0, 4]})"), 4),
            "'a' has dtype I32; weight tensors must be F32 or F16");
    }
    SECTION("wrong shape on lookup") {
        WeightStore w = WeightStore::from_file(SafetensorsFile::parse(raw_file(header_with(ok), 24), "bad.safetensors"));
        REQUIRE_THROWS_WITH(w.get("a", {3, 2}), Catch::Contains("weight 'a' has shape [2, 3], expected [3, 2]"));
        REQUIRE_THROWS_WITH(w.get("b", {1}), Catch::Contains("weight 'b' is missing"));
    }
}

TEST_CASE("an unreadable weight file is named", "[weights]") {
    REQUIRE_THROWS_WITH(WeightStore::load("/nonexistent/model.safetensors"),
                        Catch::Contains("/nonexistent/model.safetensors: cannot open file"));
    // A directory: named as one (libstdc++ opens it and reports a size, which read as a huge buffer).
    const std::string dir = test::temp_path("a_weights_dir");
    std::filesystem::create_directories(dir);
    REQUIRE_THROWS_WITH(WeightStore::load(dir), Catch::Contains(dir + ": is a directory, not a safetensors weight file"));
}

TEST_CASE("WeightStore::load: a file that is not tensors says it is likely no weight file; a missing one does not",
          "[weights]") {
    // vtloc-bench loads weights this way: a calibration or JSON given as --weights printed only
    // the header length it read from the first 8 bytes.
    const std::string text = test::temp_path("weights_text.safetensors");
    std::ofstream(text) << "{\"not\": \"weights\"}\n";
    REQUIRE_THROWS_WITH(WeightStore::load(text), Catch::Contains(text) && Catch::Contains("(not a safetensors weight file?)"));
    const std::string missing = test::temp_path("weights_missing.safetensors");
    REQUIRE_THROWS_WITH(WeightStore::load(missing), Catch::Contains(missing) && !Catch::Contains("not a safetensors"));
}
