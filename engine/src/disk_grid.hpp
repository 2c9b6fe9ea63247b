#pragma once
// Disks of one radius in a grid of g x g square cells at least s = 2r wide, a linked list per cell:
// every disk closer than s to a point lies in the 3 x 3 cells around it, so a query costs O(1)
// expected for scenes without pile-ups. Random placement (rejecting overlapping draws) and the
// overlap check of a given scene both use it: O(N) expected to build and query.
//
// The overlap test runs in a power-of-two unit near s (exact scaling, the same decisions as in the
// scene's units wherever those neither underflow nor overflow): s * s underflows to 0 for r below
// about 1e-162, and would then find no overlap at all.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "particle/particles.hpp"

namespace particle::detail {

class DiskGrid {
 public:
  // A grid for up to n disks of contact distance s in [0, L]^2: about one cell per disk, none
  // narrower than s.
  DiskGrid(double L, double s, std::size_t n)
      : g_(static_cast<std::int64_t>(std::max(
            1.0, std::min(std::floor(L / s), std::ceil(std::sqrt(static_cast<double>(n))))))),
        cell_(L / static_cast<double>(g_)),
        unit_(std::ldexp(1.0, -std::max(std::ilogb(s), DBL_MIN_EXP - 1))),
        s2_((s * unit_) * (s * unit_)),
        head_(static_cast<std::size_t>(g_ * g_), -1),
        next_(n, -1) {}

  // Adds disk i, whose centre p.x[i], p.y[i] is set.
  void insert(const Particles& p, std::size_t i) {
    const std::int64_t c = cell_of(p.y[i]) * g_ + cell_of(p.x[i]);
    next_[i] = head_[static_cast<std::size_t>(c)];
    head_[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(i);
  }

  // Calls visit(k) for every inserted disk k whose centre is closer than s to (x, y); stops and
  // returns true as soon as visit returns true.
  template <class Visit>
  bool any_closer(const Particles& p, double x, double y, Visit&& visit) const {
    const std::int64_t cx = cell_of(x), cy = cell_of(y);
    for (std::int64_t gy = std::max<std::int64_t>(0, cy - 1); gy <= std::min(g_ - 1, cy + 1); ++gy)
      for (std::int64_t gx = std::max<std::int64_t>(0, cx - 1); gx <= std::min(g_ - 1, cx + 1);
           ++gx)
        for (std::int64_t k = head_[static_cast<std::size_t>(gy * g_ + gx)]; k >= 0;
             k = next_[static_cast<std::size_t>(k)]) {
          const double dx = (p.x[k] - x) * unit_, dy = (p.y[k] - y) * unit_;
          if (dx * dx + dy * dy < s2_ && visit(static_cast<std::size_t>(k))) return true;
        }
    return false;
  }

 private:
  std::int64_t cell_of(double c) const {
    return std::min(g_ - 1, static_cast<std::int64_t>(c / cell_));
  }

  std::int64_t g_;
  double cell_;
  double unit_;  // a power of two near 1/s
  double s2_;    // (s * unit)^2
  std::vector<std::int64_t> head_, next_;
};

}  // namespace particle::detail
