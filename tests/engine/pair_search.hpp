#pragma once
// A broad phase run alone on a World: its candidates and counts, for the tests that compare
// broad phases with brute's (test_engines_pairs.cpp, test_bands.cpp).
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <tuple>
#include <vector>

#include "broad_phase/common.hpp"
#include "world.hpp"

namespace particle::testing {

struct Found {
  std::vector<std::tuple<std::uint32_t, std::uint32_t, double>> candidates;  // sorted
  std::vector<std::tuple<std::uint32_t, std::uint32_t, double>> receding;    // sorted
  std::uint64_t pair_tests = 0, overlaps = 0;
};

// Runs one broad phase's prepare + find_pairs on `threads` threads, `rounds` times on the same
// state (so a broad phase that plans from the previous sub-step is exercised too); the last
// round's findings.
template <class Broad>
Found find(Broad& broad, const detail::World& w, int threads, int rounds = 2) {
  Found last;
  for (int round = 0; round < rounds; ++round) {
    std::vector<detail::ThreadScratch> scratch(threads);
#pragma omp parallel num_threads(threads)
    {
      broad.prepare(w);
      detail::find_pairs(broad, w, scratch[omp_get_thread_num()]);
    }
    Found f;
    for (const detail::ThreadScratch& s : scratch) {
      for (const Candidate& c : s.candidates) f.candidates.emplace_back(c.i, c.j, c.t);
      for (const Candidate& c : s.receding) f.receding.emplace_back(c.i, c.j, c.t);
      f.pair_tests += s.pair_tests;
      f.overlaps += s.overlaps;
    }
    std::sort(f.candidates.begin(), f.candidates.end());
    std::sort(f.receding.begin(), f.receding.end());
    last = f;
  }
  return last;
}

}  // namespace particle::testing
