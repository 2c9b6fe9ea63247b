// Random scenes: positions uniform in [r, L-r]^2 without overlap, found by rejection against a
// grid of cells at least s wide (3x3 cells hold every possible overlap), so placement is O(N)
// expected. A particle that fails kMaxAttempts times means the box is too full: an error, never
// an endless loop.
#include "particle/random_scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <string>

namespace particle {

namespace {
constexpr int kMaxAttempts = 1000;
}

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
  const double sides = std::min(std::floor(L / s), std::ceil(std::sqrt(static_cast<double>(n))));
  const auto g = static_cast<std::int64_t>(std::max(1.0, sides));
  const double cell = L / static_cast<double>(g);
  std::vector<std::int64_t> head(static_cast<std::size_t>(g * g), -1), next(n, -1);
  const auto cell_of = [&](double c) {
    return std::min(g - 1, static_cast<std::int64_t>(c / cell));
  };
  // The overlap test in units of a power of two near s (exact scaling, the same decisions as in
  // the scene's units wherever those neither underflow nor overflow): s * s underflows to 0 for
  // r below about 1e-162, and would then let every particle overlap.
  const double unit = std::ldexp(1.0, -std::max(std::ilogb(s), DBL_MIN_EXP - 1));
  const double s_scaled = s * unit;
  const auto overlaps = [&](double x, double y) {
    const std::int64_t cx = cell_of(x), cy = cell_of(y);
    for (std::int64_t gy = std::max<std::int64_t>(0, cy - 1); gy <= std::min(g - 1, cy + 1); ++gy)
      for (std::int64_t gx = std::max<std::int64_t>(0, cx - 1); gx <= std::min(g - 1, cx + 1); ++gx)
        for (std::int64_t k = head[gy * g + gx]; k >= 0; k = next[k]) {
          const double dx = (p.x[k] - x) * unit, dy = (p.y[k] - y) * unit;
          if (dx * dx + dy * dy < s_scaled * s_scaled) return true;
        }
    return false;
  };

  Random rng(init.seed);
  for (std::size_t i = 0; i < n; ++i) {
    int attempt = 0;
    double x, y;
    do {
      if (++attempt > kMaxAttempts)
        throw InputError(fmt::format(
            "scene too dense for random placement: placed {} of {} particles of radius {:g} in a "
            "box of {:g} (give fewer or smaller particles, or a larger box)",
            i, n, r, L));
      // min(): r + u * span may round one ulp past the wall line.
      x = std::min(r + rng.uniform() * span, L - r);
      y = std::min(r + rng.uniform() * span, L - r);
    } while (overlaps(x, y));
    p.x[i] = x;
    p.y[i] = y;
    const std::int64_t c = cell_of(y) * g + cell_of(x);
    next[i] = head[c];
    head[c] = static_cast<std::int64_t>(i);
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
