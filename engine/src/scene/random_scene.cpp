// Random scenes: positions uniform in [r, L-r]^2 without overlap, the sequential rejection rule's
// (each draw refused when a disk placed before it is closer than s), decided in batches sorted by
// cell (scene/placement.cpp), so placement is O(N) expected; then speeds. A particle that fails
// kMaxPlacementAttempts times means the box is too full: an error, never an endless loop.
#include "particle/random_scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "scene/placement.hpp"

namespace particle {

SpeedRange default_speed_range(double L, double r) {
  return {std::min(L / (8 * r), L / 4), std::max(L / (8 * r), L / 4)};
}

void place_random(Scene& scene, const RandomInit& init, int threads) {
  Particles& p = scene.particles;
  const std::size_t n = p.size();
  const double L = scene.L, r = scene.r;
  const detail::Placement placed =
      detail::place_positions(p, L, r, scene.contact_distance(), init.seed, threads);
  if (placed.placed < n)
    throw InputError(fmt::format(
        "scene too dense for random placement: placed {} of {} particles of radius {:g} in a box "
        "of {:g} (give fewer or smaller particles, or a larger box)",
        placed.placed, n, r, L));

  // The speeds take the draws after the last position tested.
  draw_speeds(p, init.seed, placed.taken, init.speed.value_or(default_speed_range(L, r)));
}

void draw_speeds(Particles& p, std::uint64_t seed, std::uint64_t taken, const SpeedRange& range) {
  Random rng(seed);
  rng.discard(2 * taken);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double speed = range.min + rng.uniform() * (range.max - range.min);
    double dx, dy, q;
    do {
      dx = 2 * rng.uniform() - 1;
      dy = 2 * rng.uniform() - 1;
      q = dx * dx + dy * dy;
    } while (q > 1 || q == 0);
    const double norm = std::sqrt(q);
    p.vx[i] = speed * dx / norm;
    p.vy[i] = speed * dy / norm;
  }
}

}  // namespace particle
