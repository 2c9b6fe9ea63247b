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

namespace {
constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ull;
}

void Random::discard(std::uint64_t k) { state_ += k * kGolden; }

std::uint64_t Random::next() {
  std::uint64_t z = (state_ += kGolden);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

double Random::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

namespace {

struct Draw {
  double x, y;
};

// The draws' positions in order, made kAhead draws before they are tested: they do not depend on
// which draws are refused. Where the grid lies beyond the caches, each draw's cells are asked for
// as it is made, and halfway to its test the first disk of each, so that its misses (the
// placement's whole cost there) are under way before it is tested.
class Draws {
 public:
  Draws(const detail::DiskGrid& grid, std::uint64_t seed, double r, double L)
      : grid_(grid), prefetch_(grid.bytes() > kCachedBytes), rng_(seed), r_(r), L_(L) {
    for (std::size_t k = 0; k < kAhead; ++k) make(k);
  }

  // The next draw's position.
  Draw next() {
    const Draw d = ring_[taken_ % kAhead];
    if (prefetch_) {
      const Draw& halfway = ring_[(taken_ + kAhead / 2) % kAhead];
      grid_.prefetch_disks(halfway.x, halfway.y);
    }
    make(taken_ + kAhead);
    ++taken_;
    return d;
  }

  std::size_t taken() const { return taken_; }

 private:
  static constexpr std::size_t kAhead = 16;
  static constexpr std::size_t kCachedBytes = std::size_t{4} << 20;  // a large L2, a small L3

  // Draw k's position: uniform in [r, L - r]^2. min(): r + u * span may round one ulp past the
  // wall line.
  void make(std::size_t k) {
    const double span = L_ - 2 * r_;
    Draw& d = ring_[k % kAhead];
    d.x = std::min(r_ + rng_.uniform() * span, L_ - r_);
    d.y = std::min(r_ + rng_.uniform() * span, L_ - r_);
    if (prefetch_) grid_.prefetch_cells(d.x, d.y);
  }

  const detail::DiskGrid& grid_;
  const bool prefetch_;
  Random rng_;
  double r_, L_;
  Draw ring_[kAhead];
  std::size_t taken_ = 0;
};

}  // namespace

void place_random(Scene& scene, const RandomInit& init) {
  Particles& p = scene.particles;
  const std::size_t n = p.size();
  const double L = scene.L, r = scene.r;
  detail::DiskGrid placed(L, scene.contact_distance(), n);
  Draws draws(placed, init.seed, r, L);
  for (std::size_t i = 0; i < n; ++i) {
    int attempt = 0;
    Draw d;
    do {
      if (++attempt > kMaxPlacementAttempts)
        throw InputError(fmt::format(
            "scene too dense for random placement: placed {} of {} particles of radius {:g} in a "
            "box of {:g} (give fewer or smaller particles, or a larger box)",
            i, n, r, L));
      d = draws.next();
    } while (placed.any_closer(d.x, d.y));
    p.x[i] = d.x;
    p.y[i] = d.y;
    placed.insert(p, i);
  }

  // The speeds take the draws after the last position tested, two numbers a draw.
  Random rng(init.seed);
  rng.discard(2 * draws.taken());
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
