#pragma once
// Overlapping particles in a given scene. The model lets them be (an approaching pair collides at
// once, a receding one passes through), but in a scene file they are usually a mistake: psim
// warns with what this finds.
#include <cstddef>
#include <cstdint>

#include "particle/scene.hpp"

namespace particle {

struct Overlaps {
  std::uint64_t pairs = 0;               // pairs whose centres are closer than s = 2r
  std::size_t first_i = 0, first_j = 0;  // the first such pair in (i, j) order, i < j
};

// The engine's overlap test (distance < s) in an exact power-of-two unit, so it holds at every
// scale; O(N) expected through a grid of cells at least s wide (O(N^2) only where every particle
// overlaps every other, as a sub-step of such a scene costs anyway). On `threads` OpenMP threads
// (0: OpenMP's default) save the sort by cell; the same result for any count.
Overlaps find_overlaps(const Scene& scene, int threads = 1);

}  // namespace particle
