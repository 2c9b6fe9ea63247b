// Resolve: move each accepted collision's particles to its time t, apply it, then move them for
// the rest of the sub-step, stopping at a wall line rather than crossing it (the particle then
// collides in the next sub-step). A pair exchanges the velocity components along the unit normal
// of its actual separation, which conserves energy and momentum to rounding.
// O(accepted); accepted collisions share no particle, so they run in parallel in any split.
#include <algorithm>

#include "contact.hpp"
#include "step/stages.hpp"

namespace particle::detail {
namespace {

void resolve_wall(const World& w, const Candidate& c) {
  const std::uint32_t i = c.i;
  double x = move_clamped(w.x[i], w.ux[i], c.t, w.lo, w.hi);
  double y = move_clamped(w.y[i], w.uy[i], c.t, w.lo, w.hi);
  w.wall_impulse[i] += bounce_off_wall(c.j, w.ux[i], w.uy[i]);
  w.x[i] = move_clamped(x, w.ux[i], 1 - c.t, w.lo, w.hi);
  w.y[i] = move_clamped(y, w.uy[i], 1 - c.t, w.lo, w.hi);
  ++w.wall_collisions[i];
}

void resolve_pair(const World& w, const Candidate& c) {
  const std::uint32_t i = c.i, j = c.j;
  const double xi = move_clamped(w.x[i], w.ux[i], c.t, w.lo, w.hi);
  const double yi = move_clamped(w.y[i], w.uy[i], c.t, w.lo, w.hi);
  const double xj = move_clamped(w.x[j], w.ux[j], c.t, w.lo, w.hi);
  const double yj = move_clamped(w.y[j], w.uy[j], c.t, w.lo, w.hi);
  exchange_along_normal(xj - xi, yj - yi, w.ux[i], w.uy[i], w.ux[j], w.uy[j]);
  const double rest = 1 - c.t;
  w.x[i] = move_clamped(xi, w.ux[i], rest, w.lo, w.hi);
  w.y[i] = move_clamped(yi, w.uy[i], rest, w.lo, w.hi);
  w.x[j] = move_clamped(xj, w.ux[j], rest, w.lo, w.hi);
  w.y[j] = move_clamped(yj, w.uy[j], rest, w.lo, w.hi);
  ++w.pair_collisions[i];
  ++w.pair_collisions[j];
}

}  // namespace

void resolve_collisions(const World& w, const std::vector<Candidate>& accepted, std::size_t first,
                        std::size_t last) {
  last = std::min(last, accepted.size());
  for (std::size_t k = first; k < last; ++k) {
    if (is_wall(accepted[k]))
      resolve_wall(w, accepted[k]);
    else
      resolve_pair(w, accepted[k]);
  }
}

}  // namespace particle::detail
