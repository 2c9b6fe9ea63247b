#pragma once
// Brute broad phase: every pair, O(N^2) per sub-step. The reference every other engine is tested
// against, and the 2019 report's sequential and OpenMP versions.
//
// Balance: row i of the triangle has N-1-i pairs; row k is folded with row N-1-k so every folded
// row has N-1 pairs. Threads take small dynamic chunks of folded rows: on a quiet machine that is
// as even as a static split, and a thread that shares its core (more threads than cores, or a
// busy neighbour) takes fewer chunks instead of holding everyone up.
#include <string>

#include "narrow_phase.hpp"

namespace particle::detail {

struct BruteBroadPhase {
  void prepare(const World&) {}

  void find_pairs(const World& w, ThreadScratch& out) {
    const auto n = static_cast<std::uint32_t>(w.n);
    const std::uint32_t folded = (n + 1) / 2;
#pragma omp for schedule(dynamic, 4) nowait
    for (std::uint32_t k = 0; k < folded; ++k) {
      test_row(w, k, k + 1, n, out);
      const std::uint32_t mirror = n - 1 - k;
      if (mirror != k) test_row(w, mirror, mirror + 1, n, out);
    }
  }

  std::string name() const { return "brute"; }
};

}  // namespace particle::detail
