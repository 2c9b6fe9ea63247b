#pragma once
#include <cstdint>

#include "particle/io.hpp"
#include "particle/scene.hpp"

namespace particle {

// Portable seeded generator: SplitMix64, doubles from the top 53 bits, directions by rejection
// from the unit disc (no libm transcendental functions), so a seed gives the same scene everywhere.
// Inline: random placement makes each draw's position from its place in the stream, several
// times a draw.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += kGolden);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  // As k calls of next() would leave it (a counter: the state moves by one constant a draw).
  void discard(std::uint64_t k) { state_ += k * kGolden; }

 private:
  static constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ull;
  std::uint64_t state_;
};

// The 2019 speed range: between L/(8r) and L/4, the smaller first.
SpeedRange default_speed_range(double L, double r);

// Draws a position for one particle at most this many times before the box counts as too full.
inline constexpr int kMaxPlacementAttempts = 1000;

// Fills scene.particles (N already sized) with non-overlapping positions in [r, L-r]^2 and
// speeds uniform in the range; O(N) expected via a grid, the positions decided on `threads`
// threads (the same scene on any number). Throws InputError when the box is too full to place
// them.
void place_random(Scene& scene, const RandomInit& init, int threads = 1);

// place_random's speeds: each particle's from the generator's numbers after the first `taken`
// draws (two numbers a draw, the positions'), uniform in `range`, its direction by rejection from
// the unit disc.
void draw_speeds(Particles& p, std::uint64_t seed, std::uint64_t taken, const SpeedRange& range);

}  // namespace particle
