#pragma once
// Disks of one radius in a grid of g x g square cells at least s = 2r wide: every disk closer than
// s to a point lies in the 3 x 3 cells around it. Random placement (DiskGrid: a linked list per
// cell, disks added one at a time, rejecting overlapping draws) and the overlap check of a given
// scene (find_overlaps: all disks sorted by cell at once) both use this geometry: O(N) expected.
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

class DiskCells {
 public:
  // About one cell per disk for up to n disks in [0, L]^2, none narrower than s.
  DiskCells(double L, double s, std::size_t n)
      : g_(static_cast<std::int64_t>(std::max(
            1.0, std::min(std::floor(L / s), std::ceil(std::sqrt(static_cast<double>(n))))))),
        cell_(L / static_cast<double>(g_)),
        unit_(std::ldexp(1.0, -std::max(std::ilogb(s), DBL_MIN_EXP - 1))),
        s2_((s * unit_) * (s * unit_)) {}

  std::int64_t side() const { return g_; }
  std::int64_t cell_of(double c) const {
    return std::min(g_ - 1, static_cast<std::int64_t>(c / cell_));
  }
  // Centres (x1, y1) and (x2, y2) closer than s.
  bool closer(double x1, double y1, double x2, double y2) const {
    const double dx = (x1 - x2) * unit_, dy = (y1 - y2) * unit_;
    return dx * dx + dy * dy < s2_;
  }

 private:
  std::int64_t g_;
  double cell_;
  double unit_;  // a power of two near 1/s
  double s2_;    // (s * unit)^2
};

class DiskGrid {
 public:
  DiskGrid(double L, double s, std::size_t n)
      : cells_(L, s, n),
        head_(static_cast<std::size_t>(cells_.side() * cells_.side()), -1),
        next_(n, -1) {}

  // Adds disk i, whose centre p.x[i], p.y[i] is set.
  void insert(const Particles& p, std::size_t i) {
    const std::int64_t c = cells_.cell_of(p.y[i]) * cells_.side() + cells_.cell_of(p.x[i]);
    next_[i] = head_[static_cast<std::size_t>(c)];
    head_[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(i);
  }

  // Whether an inserted disk's centre is closer than s to (x, y).
  bool any_closer(const Particles& p, double x, double y) const {
    const std::int64_t g = cells_.side(), cx = cells_.cell_of(x), cy = cells_.cell_of(y);
    for (std::int64_t gy = std::max<std::int64_t>(0, cy - 1); gy <= std::min(g - 1, cy + 1); ++gy)
      for (std::int64_t gx = std::max<std::int64_t>(0, cx - 1); gx <= std::min(g - 1, cx + 1); ++gx)
        for (std::int64_t k = head_[static_cast<std::size_t>(gy * g + gx)]; k >= 0;
             k = next_[static_cast<std::size_t>(k)])
          if (cells_.closer(p.x[k], p.y[k], x, y)) return true;
    return false;
  }

 private:
  DiskCells cells_;
  std::vector<std::int64_t> head_, next_;
};

}  // namespace particle::detail
