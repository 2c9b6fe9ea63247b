// Wall candidates: per particle and axis, the fraction of the sub-step at which its centre reaches
// a wall line; the earlier axis wins and equal times are a corner. O(N), independent per particle,
// so any split across threads yields the same set. A particle at rest or sliding along a wall has
// u == 0 on that axis and never counts as a hit (its 0/0 or x/0 is discarded by a select).
//
// Branch-free: about a fifth of the particles hit a wall in a sub-step of the default scene, in no
// pattern a branch predictor can learn, so the times are computed with selects and the candidates
// written unconditionally to the next free slot, which only advances on a hit.
#include <omp.h>

#include <algorithm>
#include <limits>

#include "stages.hpp"

namespace particle::detail {
namespace {

// A negative time (at or past the line, moving out) becomes 0: it hits now.
inline double axis_time(double x, double u, double lo, double hi) {
  const double t = std::max(0.0, ((u > 0 ? hi : lo) - x) / u);
  return u != 0 ? t : std::numeric_limits<double>::infinity();
}

}  // namespace

void find_wall_candidates(const World& w, ThreadScratch& out) {
  const int threads = omp_get_num_threads(), t = omp_get_thread_num();
  const std::size_t lo = w.n * t / threads, hi = w.n * (t + 1) / threads;
  std::vector<Candidate>& c = out.candidates;
  const std::size_t base = c.size();
  c.resize(base + (hi - lo));
  std::size_t used = base;
  for (std::size_t i = lo; i < hi; ++i) {
    const double tx = axis_time(w.x[i], w.ux[i], w.lo, w.hi);
    const double ty = axis_time(w.y[i], w.uy[i], w.lo, w.hi);
    const std::uint32_t kind = tx < ty ? kWallX : (ty < tx ? kWallY : kWallCorner);
    c[used] = {std::min(tx, ty), static_cast<std::uint32_t>(i), kind};
    used += c[used].t <= 1;
  }
  c.resize(used);
}

}  // namespace particle::detail
