// The symmetry declaration's JSON form (object.json's "symmetry"), apart from the
// geometry in symmetry.cpp: the reader is fuzzed (tests/fuzz/fuzz_dataset.cpp), and
// libFuzzer's coverage is compiled into its file alone.
#include "engine/sim/symmetry.h"

#include <cmath>

#include "base/error.h"

namespace vtloc::sim {

namespace {

double norm2(const Vec3d& a) { return a[0] * a[0] + a[1] * a[1] + a[2] * a[2]; }

Vec3d unit(const Vec3d& a) {
    const double n = std::sqrt(norm2(a));
    return {a[0] / n, a[1] / n, a[2] / n};
}

// An axis given finite but so long that its squared length overflows would normalise to
// zero and pass as a direction.
void check_direction(const Vec3d& a, const std::string& where, const char* what) {
    const double n2 = norm2(a);
    if (n2 < 1e-12) throw Error(where + ": symmetry " + what + " is zero");
    if (!std::isfinite(n2)) throw Error(where + ": symmetry " + what + " is too long to normalise");
}

}  // namespace

nlohmann::json symmetry_json(const Symmetry& s) {
    if (s.none()) return nullptr;
    if (s.all) return nlohmann::json{{"point", s.point}, {"all", true}};
    nlohmann::json j{{"point", s.point}, {"axis", s.axis}, {"order", s.order}};
    j["flip"] = s.flip ? nlohmann::json(*s.flip) : nlohmann::json(nullptr);
    return j;
}

Symmetry symmetry_from_json(const nlohmann::json& j, const std::string& where) {
    Symmetry s;
    if (j.is_null()) return s;
    auto vec = [&](const nlohmann::json& v, const char* what) {
        if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
            throw Error(where + ": symmetry \"" + what + "\" must be [x, y, z]");
        Vec3d o{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
        for (double x : o)
            if (!std::isfinite(x)) throw Error(where + ": symmetry \"" + what + "\" is not finite");
        return o;
    };
    if (j.is_object() && j.contains("all")) {  // every rotation about a point
        if (!j["all"].is_boolean() || !j["all"].get<bool>() || !j.contains("point") || j.size() != 2)
            throw Error(where + ": a spherical symmetry is {\"point\": [x, y, z], \"all\": true}");
        s.point = vec(j["point"], "point");
        s.all = true;
        return s;
    }
    if (!j.is_object() || !j.contains("point") || !j.contains("axis") || !j.contains("order"))
        throw Error(where + ": symmetry must be null, {\"point\", \"axis\", \"order\", \"flip\"} or {\"point\", \"all\": true}");
    s.point = vec(j["point"], "point");
    s.axis = vec(j["axis"], "axis");
    check_direction(s.axis, where, "axis");
    s.axis = unit(s.axis);
    if (!j["order"].is_number_integer() || j["order"].get<int>() < 0 || j["order"].get<int>() > 3600)
        throw Error(where + ": symmetry order must be an integer 0..3600 (0: every angle)");
    s.order = j["order"].get<int>();
    if (j.contains("flip") && !j["flip"].is_null()) {
        Vec3d f = vec(j["flip"], "flip");
        check_direction(f, where, "flip axis");
        f = unit(f);
        if (std::abs(f[0] * s.axis[0] + f[1] * s.axis[1] + f[2] * s.axis[2]) > 1e-3)
            throw Error(where + ": symmetry flip axis must be perpendicular to the axis");
        s.flip = f;
    }
    return s;
}

}  // namespace vtloc::sim
