#pragma once
// Disks of one radius in a grid of g x g square cells at least s = 2r wide: every disk closer than
// s to a point lies in the 3 x 3 cells around it. Random placement (DiskGrid: a linked list per
// cell, disks added one at a time, rejecting overlapping draws) and the overlap check of a given
// scene (find_overlaps: all disks sorted by cell at once) both use this geometry: O(N) expected.
// How many cells a disk: find_overlaps sorts every disk by cell and wants few cells; DiskGrid's
// draws land at random in arrays beyond the caches, where each disk looked at costs a miss, and it
// takes cells as narrow as s (up to four a disk) so that the 3 x 3 cells hold fewer disks.
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
  // About `per_disk` cells per disk for up to n disks in [0, L]^2, none narrower than s.
  DiskCells(double L, double s, std::size_t n, double per_disk = 1)
      : g_(static_cast<std::int64_t>(std::max(
            1.0, std::min(std::floor(L / s),
                          std::ceil(std::sqrt(per_disk * static_cast<double>(n))))))),
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
      : cells_(L, s, n, 4),
        head_(static_cast<std::size_t>(cells_.side() * cells_.side()), kNone),
        disks_(n) {}

  // Adds disk i, whose centre p.x[i], p.y[i] is set.
  void insert(const Particles& p, std::size_t i) {
    const std::int64_t c = cells_.cell_of(p.y[i]) * cells_.side() + cells_.cell_of(p.x[i]);
    disks_[i] = {p.x[i], p.y[i], head_[static_cast<std::size_t>(c)]};
    head_[static_cast<std::size_t>(c)] = static_cast<std::uint32_t>(i);
  }

  std::size_t bytes() const {
    return head_.size() * sizeof(std::uint32_t) + disks_.size() * sizeof(Disk);
  }

  // Whether an inserted disk's centre is closer than s to (x, y).
  bool any_closer(double x, double y) const {
    return any_cell_around(x, y, [&](std::size_t c) {
      for (std::uint32_t k = head_[c]; k != kNone; k = disks_[k].next)
        if (cells_.closer(disks_[k].x, disks_[k].y, x, y)) return true;
      return false;
    });
  }

  // Hints for a later any_closer(x, y): its cells' heads, then (once those have come) the first
  // disk of each. Always inlined: GCC takes a function that does nothing but prefetch for one
  // without effects, and deletes its calls.
  [[gnu::always_inline]] void prefetch_cells(double x, double y) const {
    any_cell_around(x, y, [&](std::size_t c) {
      __builtin_prefetch(&head_[c]);
      return false;
    });
  }
  [[gnu::always_inline]] void prefetch_disks(double x, double y) const {
    any_cell_around(x, y, [&](std::size_t c) {
      if (head_[c] != kNone) __builtin_prefetch(&disks_[head_[c]]);
      return false;
    });
  }

 private:
  // Whether `found` holds for one of the 3 x 3 cells around (x, y), asked in row order.
  template <class Found>
  [[gnu::always_inline]] bool any_cell_around(double x, double y, Found found) const {
    const std::int64_t g = cells_.side(), cx = cells_.cell_of(x), cy = cells_.cell_of(y);
    for (std::int64_t gy = std::max<std::int64_t>(0, cy - 1); gy <= std::min(g - 1, cy + 1); ++gy)
      for (std::int64_t gx = std::max<std::int64_t>(0, cx - 1); gx <= std::min(g - 1, cx + 1); ++gx)
        if (found(static_cast<std::size_t>(gy * g + gx))) return true;
    return false;
  }

  static constexpr std::uint32_t kNone = UINT32_MAX;  // a scene holds at most 10^8 disks

  // A disk's centre beside its link: one miss a disk looked at, where the centre's own arrays
  // and the link's cost three.
  struct Disk {
    double x, y;
    std::uint32_t next;
  };

  DiskCells cells_;
  std::vector<std::uint32_t> head_;
  std::vector<Disk> disks_;
};

}  // namespace particle::detail
