// vtloc eval: which objects a weight file was trained on, from its metadata
// (`vtloc.provenance`, JSON), to warn when "unknown" objects are not unknown.
#include <nlohmann/json.hpp>

#include "apps/vtloc/eval.h"
#include "base/error.h"
#include "engine/safetensors.h"

namespace vtloc::cli::eval {

std::optional<std::vector<std::string>> trained_objects(const std::string& model_path) {
    std::map<std::string, std::string> meta;
    try {
        meta = SafetensorsFile::load(model_path).metadata();
    } catch (const vtloc::Error& e) {
        throw api::Error(e.what());
    }
    auto it = meta.find("vtloc.provenance");
    if (it == meta.end()) return std::nullopt;
    const nlohmann::json p = nlohmann::json::parse(it->second, nullptr, false);
    if (!p.is_object()) return std::nullopt;  // unreadable provenance: nothing to check against
    std::vector<std::string> names;
    bool listed = false;
    if (auto t = p.find("train_objects"); t != p.end() && t->is_array()) {
        listed = true;
        for (const auto& n : *t)
            if (n.is_string()) names.push_back(n.get<std::string>());
    }
    if (auto o = p.find("objects"); o != p.end() && o->is_array()) {
        listed = true;
        for (const auto& e : *o) {
            if (e.is_string()) {
                names.push_back(e.get<std::string>());
            } else if (e.is_object() && e.contains("name") && e["name"].is_string()) {
                // Objects listed with their split: only the "seen" ones were trained on.
                const bool seen = !e.contains("object_split") || e["object_split"] == "seen";
                if (seen) names.push_back(e["name"].get<std::string>());
            }
        }
    }
    if (!listed) return std::nullopt;
    return names;
}

}  // namespace vtloc::cli::eval
