// Wall candidates: per particle and axis, the fraction of the sub-step at which its centre reaches
// a wall line; the earlier axis wins and equal times are a corner. O(N), independent per particle,
// so any split across threads yields the same set. A particle at rest or sliding along a wall has
// u == 0 on that axis and never divides.
#include <algorithm>
#include <limits>

#include "stages.hpp"

namespace particle::detail {
namespace {

// A negative time (at or past the line, moving out) becomes 0: it hits now.
double axis_time(double x, double u, double lo, double hi) {
  if (u > 0) return std::max(0.0, (hi - x) / u);
  if (u < 0) return std::max(0.0, (lo - x) / u);
  return std::numeric_limits<double>::infinity();
}

}  // namespace

void find_wall_candidates(const World& w, ThreadScratch& out) {
  const auto n = static_cast<std::uint32_t>(w.n);
#pragma omp for schedule(static) nowait
  for (std::uint32_t i = 0; i < n; ++i) {
    const double tx = axis_time(w.x[i], w.ux[i], w.lo, w.hi);
    const double ty = axis_time(w.y[i], w.uy[i], w.lo, w.hi);
    const double t = std::min(tx, ty);
    if (!(t <= 1)) continue;
    const std::uint32_t kind = tx < ty ? kWallX : (ty < tx ? kWallY : kWallCorner);
    out.candidates.push_back({t, i, kind});
  }
}

}  // namespace particle::detail
