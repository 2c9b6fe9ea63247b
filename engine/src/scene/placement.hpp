#pragma once
// The positions of a random scene (place_random, scene/random_scene.cpp): the one-at-a-time
// rejection rule's, decided in batches of draws sorted by cell (scene/placement.cpp).
#include <cstddef>
#include <cstdint>

#include "particle/particles.hpp"

namespace particle::detail {

// How far placement got: `placed` particles, all of them unless one's kMaxPlacementAttempts draws
// were all refused, and the draws `taken` up to the last one placed.
struct Placement {
  std::size_t placed = 0;
  std::uint64_t taken = 0;
};

// Fills p.x, p.y (sized) with the rule's positions for `seed` in a box of L, disks of radius r,
// centres closer than s refused: draw k's position is made from the generator's numbers 2k and
// 2k + 1, uniform in [r, L - r]^2, and accepted when no accepted draw before it is closer than s,
// until p.size() are accepted or a particle's kMaxPlacementAttempts draws are all refused. The
// same positions and counts on any number of threads.
Placement place_positions(Particles& p, double L, double r, double s, std::uint64_t seed,
                          int threads);

}  // namespace particle::detail
