#pragma once
// Sweep broad phase: sort-and-sweep over swept bounding boxes, for fast scenes (the default scene
// moves up to a quarter of the box per step, where cells cannot prune).
//
// Each particle's swept interval on x is [x - h, x + h] with h = |ux| + r, padded (two particles
// can only touch if |dx| <= s + |ux_i| + |ux_j|; see broad_phase_common.hpp). Particles are sorted
// by interval start; the partners of the particle at sorted position k that start after it are
// exactly positions k+1 .. (last start <= its end), one contiguous span of a sorted copy of the
// particles, which the narrow phase tests in one vectorized loop. Each overlapping pair is tested
// once, from the earlier of the two in sorted order (ties in any order: the set is the same).
//
// Sort, O(N) expected: a bucket pass on the start (id order, stable) then an insertion sort that
// finishes the nearly sorted result; if that needs more than 16 moves a particle (pathological
// clustering), std::sort does it instead. Cost per sub-step: O(N) plus the overlapping pairs, about
// 2h/L of all pairs for uniform positions (0.45 in the default scene).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "broad_phase_common.hpp"
#include "narrow_phase.hpp"

namespace particle::detail {

class SweepBroadPhase {
 public:
  void prepare(const World& w) {
    const std::size_t n = w.n;
#pragma omp single
    {
      start_.resize(n);
      bucket_.resize(n);
      if (x_.size() < n) {
        x_.resize(n);
        y_.resize(n);
        ux_.resize(n);
        uy_.resize(n);
        id_.resize(n);
        key_.resize(n);
        end_.resize(n);
      }
      buckets_.assign(n + 1, 0);
    }
    const double buckets_per_length = static_cast<double>(n) / w.L;
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < n; ++i) {
      const double h = padded(std::fabs(w.ux[i]) + w.r, w.L);
      start_[i] = w.x[i] - h;
      const double b = start_[i] * buckets_per_length;  // starts below 0 share bucket 0
      bucket_[i] = b <= 0 ? 0u : (b >= n - 1 ? static_cast<std::uint32_t>(n - 1) : static_cast<std::uint32_t>(b));
    }
#pragma omp single
    sort_by_start(n);
#pragma omp for schedule(static)
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t i = id_[k];
      x_[k] = w.x[i];
      y_[k] = w.y[i];
      ux_[k] = w.ux[i];
      uy_[k] = w.uy[i];
      end_[k] = w.x[i] + padded(std::fabs(w.ux[i]) + w.r, w.L);
    }
  }

  void find_pairs(const World& w, ThreadScratch& out) {
    const auto n = static_cast<std::uint32_t>(w.n);
    const SpanArrays a{x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()};
#pragma omp for schedule(dynamic, 16) nowait
    for (std::uint32_t k = 0; k < n; ++k) {
      const auto last = std::upper_bound(key_.begin() + k + 1, key_.begin() + n, end_[k]);
      const RowParticle p{x_[k], y_[k], ux_[k], uy_[k], id_[k]};
      test_span(p, a, k + 1, static_cast<std::uint32_t>(last - key_.begin()), w.s2, out);
    }
  }

  std::string name() const { return "sweep"; }

 private:
  // one thread: id_ and key_ sorted by interval start.
  void sort_by_start(std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) ++buckets_[bucket_[i] + 1];
    for (std::size_t b = 0; b < n; ++b) buckets_[b + 1] += buckets_[b];
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t k = buckets_[bucket_[i]]++;
      id_[k] = static_cast<std::uint32_t>(i);
      key_[k] = start_[i];
    }
    std::size_t moves = 0;
    const std::size_t budget = 16 * n + 64;
    for (std::size_t k = 1; k < n && moves <= budget; ++k) {
      const double key = key_[k];
      const std::uint32_t id = id_[k];
      std::size_t j = k;
      for (; j > 0 && key_[j - 1] > key; --j) {
        key_[j] = key_[j - 1];
        id_[j] = id_[j - 1];
      }
      moves += k - j;
      key_[j] = key;
      id_[j] = id;
    }
    if (moves > budget) {
      std::vector<std::pair<double, std::uint32_t>> pairs(n);
      for (std::size_t k = 0; k < n; ++k) pairs[k] = {key_[k], id_[k]};
      std::sort(pairs.begin(), pairs.end());
      for (std::size_t k = 0; k < n; ++k) std::tie(key_[k], id_[k]) = pairs[k];
    }
  }

  std::vector<double> start_;          // by id
  std::vector<std::uint32_t> bucket_;  // by id
  std::vector<std::uint32_t> buckets_;
  std::vector<double> key_;            // sorted interval starts
  std::vector<double> end_;            // interval ends, by sorted position
  std::vector<double> x_, y_, ux_, uy_;
  std::vector<std::uint32_t> id_;
};

}  // namespace particle::detail
