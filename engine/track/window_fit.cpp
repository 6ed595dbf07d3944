#include "engine/track/window_fit.h"

#include <cmath>

namespace vtloc::track {

using P = ops::pose::V3;

void term_row(float* r, const Rigid& rel, int steps, const FilterOptions& o, int field, double weight, double q_mm,
              double q_rad) {
    for (int i = 0; i < 9; ++i) r[i] = float(rel.R[size_t(i)]);
    for (int i = 0; i < 3; ++i) r[9 + i] = float(rel.t[size_t(i)]);
    const double lever = std::sqrt(rel.t[0] * rel.t[0] + rel.t[1] * rel.t[1] + rel.t[2] * rel.t[2]);
    const double od = o.odometry_deg * M_PI / 180;
    r[12] = float(std::sqrt(o.sigma_d_mm * o.sigma_d_mm + steps * (o.odometry_mm * o.odometry_mm + od * od * lever * lever) +
                            q_mm * q_mm + (lever * q_rad) * (lever * q_rad)));
    const double sa = o.sigma_a_deg * M_PI / 180;
    r[13] = float(std::sqrt(sa * sa + steps * od * od + q_rad * q_rad));
    r[14] = float(field);
    r[15] = float(weight);
}

ops::pose::Frame frame_of(const Rigid& x) {
    const auto& R = x.R;
    return {P{float(R[0]), float(R[3]), float(R[6])}, P{float(R[1]), float(R[4]), float(R[7])},
            P{float(R[2]), float(R[5]), float(R[8])}, P{float(x.t[0]), float(x.t[1]), float(x.t[2])}};
}

std::vector<ops::pose::Term> fit_terms(const std::vector<Rigid>& to_window, const FilterOptions& o, double q_mm, double q_rad) {
    std::vector<ops::pose::Term> terms;
    for (size_t k = 0; k < to_window.size(); ++k) {
        float r[16];
        term_row(r, to_window[k], int(to_window.size() - k), o, -1, 0, q_mm, q_rad);
        terms.push_back(ops::pose::term_from_row(r));
    }
    return terms;
}

ops::pose::Term own_term(const FilterOptions& o) {
    float r[16];
    term_row(r, Rigid{}, 0, o, -1, 0);
    return ops::pose::term_from_row(r);
}

double pose_fit(const ops::pose::Grid& grid, const std::vector<ops::pose::Term>& terms, const FilterOptions& o, const Rigid& x) {
    const ops::pose::Frame f = frame_of(x);
    const float press = float(o.press_mm), floor = float(o.log_floor), exp_floor = std::exp(floor);
    double v = 0;
    for (const ops::pose::Term& t : terms) {
        const ops::pose::Frame m = ops::pose::moved(f, t);
        v += ops::pose::geometry_log(grid, ops::pose::cell_of(grid, m.t), m, press, t.sigma_d, t.sigma_a, floor, exp_floor);
    }
    return v + double(ops::pose::geometry_log(grid, ops::pose::cell_of(grid, f.t), f, press, float(o.sigma_d_mm),
                                              float(o.sigma_a_deg * M_PI / 180), floor, exp_floor));
}

}  // namespace vtloc::track
