#pragma once
// The refinement's registration step (docs/multitouch.md, "Registration"): a window's
// contacts moved onto the surface by point-to-plane Gauss-Newton, each matched to the
// nearest dense point facing its gel at any distance. The climb's objective reads the
// lookup grid, which names points only within a few mm of the surface; at long lever arms
// a pose a few degrees off carries the far touches 5-20 mm off, where that objective is
// flat and this step still has a direction.
#include <vector>

#include "engine/ops/pose_evidence.h"
#include "engine/track/nearest_facing.h"
#include "engine/track/tracker.h"

namespace vtloc::track {

// x: a pose of the current touch; terms: the window's earlier touches seen from it (the
// refinement's tight terms: their relative poses and widths). o.register_rounds steps, the widths from
// o.register_scale times each touch's own halving down to them; each step weighs a touch
// by the robust Gaussian's own weight at those widths (an outlier beyond the floor pulls
// nothing) and is capped at 10 degrees and 10 mm. Returns x moved (x itself where fewer
// than two touches find a facing point). cap > 0: a touch's match is searched only within cap
// times its width at the round's scale (beyond about 6.7 its weight is under the step's
// cut-off anyway; the search far off the surface is most of the cost); 0: at any distance.
Rigid register_window(const NearestFacing& nearest, const std::vector<ops::pose::Term>& terms, const FilterOptions& o, Rigid x,
                      double cap = 0);

// The 6 x 6 system (H + damping) d = -g by Gaussian elimination with partial pivoting;
// false where it is singular.
bool solve6(const double H[6][6], const double g[6], double damping, double d[6]);

}  // namespace vtloc::track
