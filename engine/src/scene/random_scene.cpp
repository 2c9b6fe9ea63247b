// Random scenes: positions uniform in [r, L-r]^2 without overlap, found by rejection against a
// grid of cells at least s wide (scene/disk_grid.hpp), so placement is O(N) expected. A particle
// that fails kMaxPlacementAttempts times means the box is too full: an error, never an endless
// loop.
#include "particle/random_scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "scene/disk_grid.hpp"

namespace particle {

SpeedRange default_speed_range(double L, double r) {
  return {std::min(L / (8 * r), L / 4), std::max(L / (8 * r), L / 4)};
}

std::uint64_t Random::next() {
  std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

double Random::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

void place_random(Scene& scene, const RandomInit& init) {
  Particles& p = scene.particles;
  const std::size_t n = p.size();
  const double L = scene.L, r = scene.r, s = scene.contact_distance(), span = L - 2 * r;
  detail::DiskGrid placed(L, s, n);
  Random rng(init.seed);
  for (std::size_t i = 0; i < n; ++i) {
    int attempt = 0;
    double x, y;
    do {
      if (++attempt > kMaxPlacementAttempts)
        throw InputError(fmt::format(
            "scene too dense for random placement: placed {} of {} particles of radius {:g} in a "
            "box of {:g} (give fewer or smaller particles, or a larger box)",
            i, n, r, L));
      // min(): r + u * span may round one ulp past the wall line.
      x = std::min(r + rng.uniform() * span, L - r);
      y = std::min(r + rng.uniform() * span, L - r);
    } while (placed.any_closer(p, x, y));
    p.x[i] = x;
    p.y[i] = y;
    placed.insert(p, i);
  }

  const SpeedRange range = init.speed.value_or(default_speed_range(L, r));
  for (std::size_t i = 0; i < n; ++i) {
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
