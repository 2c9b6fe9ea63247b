#pragma once
// Brute broad phase: every pair, O(N^2) per sub-step. The reference every other engine is tested
// against, and the 2019 report's sequential and OpenMP versions.
//
// Balance: row i of the triangle has N-1-i pairs; row k is folded with row N-1-k so every folded
// row has N-1 pairs. A piece (step/pipeline.hpp) is kRows folded rows: on a quiet machine dynamic
// pieces are as even as a static split, and a thread that shares its core (more threads than
// cores, or a busy neighbour) takes fewer of them instead of holding everyone up.
#include <algorithm>
#include <string>

#include "broad_phase/common.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail {

struct BruteBroadPhase {
  void prepare(const World&) {}

  static constexpr std::uint32_t kRows = 4;

  std::uint32_t chunks(const World& w) const {
    const auto folded = static_cast<std::uint32_t>((w.n + 1) / 2);
    return (folded + kRows - 1) / kRows;
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const auto n = static_cast<std::uint32_t>(w.n);
    const std::uint32_t folded = (n + 1) / 2;
    for (std::uint32_t k = c * kRows; k < std::min(folded, (c + 1) * kRows); ++k) {
      test_row(w, k, k + 1, n, out);
      const std::uint32_t mirror = n - 1 - k;
      if (mirror != k) test_row(w, mirror, mirror + 1, n, out);
    }
  }

  std::string name() const { return "brute"; }
  std::uint64_t builds() const { return 0; }  // no structure
};

}  // namespace particle::detail
