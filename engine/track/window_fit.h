#pragma once
// How well a pose of the current touch fits the window's geometry: the term rows the step
// graph reads (term_row) and the continuous fit the refinement climbs (pose_fit), with the
// same widths. Shared by the tracker, the pair search's caller and their tests.
#include <vector>

#include "engine/ops/pose_evidence.h"
#include "engine/track/tracker.h"

namespace vtloc::track {

// The term row [16] of a touch whose pose is `rel` in the hypothesis' frame, `steps` motions
// away: rel's rotation and shift, the distance and angle widths (the surface's own, grown by
// odometry noise over the steps and by q_mm, q_rad: how far a grid hypothesis may sit from the
// true pose, half the sample spacing and half the spin step; the lever arm turns angles into
// distance), the field it reads (-1: none) and its weight.
void term_row(float* r, const Rigid& rel, int steps, const FilterOptions& o, int field, double weight, double q_mm = 0,
              double q_rad = 0);

// The window's earlier touches (poses in the current touch's frame, oldest first) as terms
// at the tight widths (q 0: a continuous pose needs no grid allowance): what the refinement
// climbs and Estimate::fit reports, with the current touch's own (pose_fit adds it).
std::vector<ops::pose::Term> fit_terms(const std::vector<Rigid>& to_window, const FilterOptions& o, double q_mm = 0,
                                       double q_rad = 0);

// The current touch's own term (its pose on the surface: the identity at the surface's
// widths), as the pair search takes it after fit_terms'.
ops::pose::Term own_term(const FilterOptions& o);

// x's rows as the pose ops read a frame.
ops::pose::Frame frame_of(const Rigid& x);

// The window's log fit of pose x of the current touch: each term's geometry at its moved pose,
// then the current touch's own at x.
double pose_fit(const ops::pose::Grid& grid, const std::vector<ops::pose::Term>& terms, const FilterOptions& o, const Rigid& x);

}  // namespace vtloc::track
