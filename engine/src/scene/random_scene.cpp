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

namespace {

struct Draw {
  double x, y;
};

// A draw's position, uniform in [r, L - r]^2. min(): r + u * span may round one ulp past the wall
// line.
Draw draw_position(Random& rng, double r, double L) {
  const double span = L - 2 * r;
  const double x = std::min(r + rng.uniform() * span, L - r);
  return {x, std::min(r + rng.uniform() * span, L - r)};
}

// The draws' positions do not depend on which of them are refused: a second generator runs
// kAhead draws ahead of the placement and asks the grid to fetch the cells each will look at, and
// halfway there their first disks, so that a draw's misses (the placement's whole cost beyond the
// caches) are under way before it is tested.
class Lookahead {
 public:
  Lookahead(const detail::DiskGrid& grid, std::uint64_t seed, double r, double L)
      : grid_(grid), rng_(seed), r_(r), L_(L) {
    for (std::size_t k = 0; k < kAhead; ++k) draw(k);
  }

  // Called as draw `k` is tested.
  void advance(std::size_t k) {
    const Draw& halfway = ring_[(k + kAhead / 2) % kAhead];
    grid_.prefetch_disks(halfway.x, halfway.y);
    draw(k + kAhead);
  }

 private:
  static constexpr std::size_t kAhead = 16;

  void draw(std::size_t k) {
    const Draw d = ring_[k % kAhead] = draw_position(rng_, r_, L_);
    grid_.prefetch_cells(d.x, d.y);
  }

  const detail::DiskGrid& grid_;
  Random rng_;
  double r_, L_;
  Draw ring_[kAhead];
};

}  // namespace

void place_random(Scene& scene, const RandomInit& init) {
  Particles& p = scene.particles;
  const std::size_t n = p.size();
  const double L = scene.L, r = scene.r;
  detail::DiskGrid placed(L, scene.contact_distance(), n);
  Random rng(init.seed);
  Lookahead ahead(placed, init.seed, r, L);
  std::size_t draws = 0;
  for (std::size_t i = 0; i < n; ++i) {
    int attempt = 0;
    Draw d;
    do {
      if (++attempt > kMaxPlacementAttempts)
        throw InputError(fmt::format(
            "scene too dense for random placement: placed {} of {} particles of radius {:g} in a "
            "box of {:g} (give fewer or smaller particles, or a larger box)",
            i, n, r, L));
      d = draw_position(rng, r, L);
      ahead.advance(draws++);
    } while (placed.any_closer(d.x, d.y));
    p.x[i] = d.x;
    p.y[i] = d.y;
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
