#include "engine/io/touch_sequence.h"

#include <string_view>

#include <nlohmann/json.hpp>

#include "engine/io/file_bytes.h"

namespace vtloc::io {

namespace {

using nlohmann::json;

double number(const json& v, const std::string& where) {
    if (!v.is_number()) throw Error(where + ": expected a number, got " + v.dump());
    return v.get<double>();
}

// A 4x4 matrix (rows) or {"Q": 3x3, "q": [3]} as a checked rigid motion.
Rigid parse_motion(const json& m, const std::string& where) {
    Rigid out;
    if (m.is_array() && m.size() == 3 && m[0].is_number())
        throw Error(where + ": a translation [dx, dy, dz] is the old translation-only format; motions are full "
                            "rigid motions now (a 4x4 matrix or {\"Q\": 3x3, \"q\": [x, y, z]})");
    if (m.is_array() && m.size() == 4) {
        std::array<double, 16> v{};
        for (size_t r = 0; r < 4; ++r) {
            if (!m[r].is_array() || m[r].size() != 4) throw Error(where + ": a 4x4 matrix needs 4 rows of 4");
            for (size_t c = 0; c < 4; ++c) v[4 * r + c] = number(m[r][c], where);
        }
        return rigid_from_rows(v, where);
    } else if (m.is_object() && m.contains("Q") && m.contains("q")) {
        const json &Q = m["Q"], &q = m["q"];
        if (!Q.is_array() || Q.size() != 3 || !q.is_array() || q.size() != 3)
            throw Error(where + ": \"Q\" must be 3 rows of 3 and \"q\" 3 numbers");
        for (size_t r = 0; r < 3; ++r) {
            if (!Q[r].is_array() || Q[r].size() != 3) throw Error(where + ": \"Q\" must be 3 rows of 3");
            for (size_t c = 0; c < 3; ++c) out.R[r * 3 + c] = number(Q[r][c], where);
            out.t[r] = number(q[r], where);
        }
    } else {
        throw Error(where + ": a motion is a 4x4 matrix or {\"Q\": 3x3, \"q\": [x, y, z]}");
    }
    check_rigid(out, where);
    return out;
}

std::string resolve(const std::filesystem::path& base, const json& v, const std::string& where) {
    if (!v.is_string() || v.get<std::string>().empty()) throw Error(where + " must be a file path");
    return (base / v.get<std::string>()).lexically_normal().string();
}

}  // namespace

std::vector<std::optional<Rigid>> TouchSequence::relative_motions(const std::string& name) const {
    std::vector<std::optional<Rigid>> out(touches.size());
    if (!flange) {
        for (size_t i = 0; i < touches.size(); ++i) out[i] = touches[i].motion;
        return out;
    }
    if (!tool) throw Error(name + ": flange poses need the tool transform (\"tool\" or --tool)");
    for (size_t i = 1; i < touches.size(); ++i) out[i] = sensor_motion(*touches[i - 1].flange, *touches[i].flange, *tool);
    return out;
}

TouchSequence parse_touch_sequence(std::string_view text, const std::filesystem::path& base, const std::string& name) {
    json j;
    try {  // the parser's reason names the spot (an out-of-range number like 1e999 included)
        j = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {
        throw Error(name + ": not valid JSON (" + e.what() + ")");
    }
    if (!j.is_object() || !j.contains("touches") || !j["touches"].is_array())
        throw Error(name + ": expected {\"format\": \"vtloc-touches/2\", \"touches\": [...]}");
    if (!j.contains("format"))
        throw Error(name + ": no \"format\": this is the old translation-only touches file; give "
                           "\"format\": \"vtloc-touches/2\" with full rigid motions (vtloc sequence --help)");
    if (j["format"] != "vtloc-touches/2") throw Error(name + ": format " + j["format"].dump() + " is not \"vtloc-touches/2\"");
    TouchSequence f;
    const json kind = j.contains("motion") ? j["motion"] : json("relative");
    if (kind != "relative" && kind != "flange") throw Error(name + ": \"motion\" must be \"relative\" or \"flange\"");
    f.flange = kind == "flange";
    if (j.contains("tool")) f.tool = parse_motion(j["tool"], name + ": tool");
    if (j.contains("object")) f.object = resolve(base, j["object"], name + ": \"object\"");
    if (j.contains("object_diameter_mm")) {
        f.object_diameter_mm = number(j["object_diameter_mm"], name + ": \"object_diameter_mm\"");
        if (!(f.object_diameter_mm > 0)) throw Error(name + ": \"object_diameter_mm\" must be > 0");
    }
    if (j.contains("where") && j["where"].is_string()) f.where = j["where"].get<std::string>();
    const json& list = j["touches"];
    for (size_t i = 0; i < list.size(); ++i) {
        const json& t = list[i];
        const std::string where = name + ": touch " + std::to_string(i + 1);
        if (!t.is_object() || !t.contains("tactile") || !t["tactile"].is_string())
            throw Error(where + " needs a \"tactile\" image path");
        SequenceTouch touch;
        touch.tactile = resolve(base, t["tactile"], where + "'s \"tactile\"");
        if (f.flange) {
            if (!t.contains("flange")) throw Error(where + " needs \"flange\" (the file's motions are flange poses)");
            touch.flange = parse_motion(t["flange"], where + "'s flange");
        } else if (t.contains("motion")) {
            if (i == 0) throw Error(where + ": the first touch has no previous one to move from; drop its motion");
            touch.motion = parse_motion(t["motion"], where + "'s motion");
        } else if (i > 0) {
            throw Error(where + " needs a \"motion\" from the previous touch");
        }
        if (t.contains("contact")) {
            const json& c = t["contact"];
            if (!c.is_array() || c.size() != 3) throw Error(where + ": \"contact\" must be [x, y, z]");
            std::array<double, 3> p{};
            for (size_t k = 0; k < 3; ++k) p[k] = number(c[k], where + ": \"contact\"");
            touch.contact = p;
        }
        f.touches.push_back(std::move(touch));
    }
    if (f.touches.empty()) throw Error(name + ": no touches");
    return f;
}

TouchSequence read_touch_sequence(const std::string& path) {
    const std::vector<uint8_t> bytes = read_file_bytes(path);  // names a missing file or a directory as such
    return parse_touch_sequence(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()),
                                std::filesystem::path(path).parent_path(), path);
}

}  // namespace vtloc::io
