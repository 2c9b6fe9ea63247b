#pragma once
#include <cstdint>

#include "particle/io.hpp"
#include "particle/scene.hpp"

namespace particle {

// Portable seeded generator: SplitMix64, doubles from the top 53 bits, directions by rejection
// from the unit disc (no libm transcendental functions), so a seed gives the same scene everywhere.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  double uniform();  // [0, 1)
  // As k calls of next() would leave it (a counter: the state moves by one constant a draw).
  void discard(std::uint64_t k);

 private:
  std::uint64_t state_;
};

// The 2019 speed range: between L/(8r) and L/4, the smaller first.
SpeedRange default_speed_range(double L, double r);

// Draws a position for one particle at most this many times before the box counts as too full.
inline constexpr int kMaxPlacementAttempts = 1000;

// Fills scene.particles (N already sized) with non-overlapping positions in [r, L-r]^2 and
// speeds uniform in the range; O(N) expected via a grid. Throws InputError when the box is too
// full to place them.
void place_random(Scene& scene, const RandomInit& init);

}  // namespace particle
