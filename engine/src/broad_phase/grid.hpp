#pragma once
// Grid broad phase: the 2019 report's "early pruning" with parameter G, made exact.
//
// The box is cut into G x G cells (CellIndex). The reach in cells is recomputed every sub-step
// from the largest displacement of that sub-step: two particles can only touch if, per axis,
// |dx| <= s + |u_i| + |u_j| <= s + 2 max|u| (padded, see broad_phase/common.hpp), so a half
// stencil of k = ceil(reach / cell) cells holds every possible pair for any G >= 1. G = 1 is
// brute force over one cell; large G with fast particles has a large k (the report assumed a
// fixed bound of L/4 per step, which collisions exceed, and dropped real collisions).
//
// Cost per sub-step: O(N + G^2) to bin, then N times the particles in a (2k+1) x (k+1) stencil.
// The candidate set is brute's; the work split (dynamic chunks of particles) never changes it.
#include <cmath>
#include <string>
#include <vector>

#include "broad_phase/cell_index.hpp"
#include "broad_phase/common.hpp"

namespace particle::detail {

class GridBroadPhase {
 public:
  // validate() bounds G to kMaxGrid: 16M cells, 64 MB of histogram per thread. A finite
  // assumed_max_displacement replaces the measured one: the unsafe 2019 pruning (grid-unsafe).
  explicit GridBroadPhase(int g, double assumed_max_displacement = INFINITY)
      : g_(g), assumed_max_(assumed_max_displacement) {}

  void prepare(const World& w) {
    const int t = omp_get_thread_num();
    SpeedStats mine;
    index_.build(
        w,
        [&] {
          index_.set_grid(g_, w.L);
          slots_.assign(omp_get_num_threads(), SpeedStats{});
        },
        [&](std::size_t lo, std::size_t hi, std::uint32_t* cells) {
          for (std::size_t i = lo; i < hi; ++i) {
            mine.add(w.ux[i], w.uy[i]);
            cells[i] = index_.cell_of(w.x[i], w.y[i]);
          }
        },
        [&] { slots_[t] = mine; },
        [&] {
          SpeedStats all;
          for (const SpeedStats& s : slots_) all.merge(s);
          const double max = std::isfinite(assumed_max_) ? assumed_max_ : all.max;
          const double cells = padded(w.s + 2 * max, w.L) / index_.cell_side();
          reach_ = cells >= g_ - 1 ? g_ - 1 : static_cast<int>(std::ceil(cells));
          ++builds_;
        });
  }

  static constexpr std::uint32_t kChunk = 32;  // particles per piece

  std::uint32_t chunks(const World&) const { return (index_.binned() + kChunk - 1) / kChunk; }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const std::uint32_t n = index_.binned();
    index_.test_half_stencils(c * kChunk, std::min(n, (c + 1) * kChunk), reach_, w.s2, out);
  }

  std::string name() const { return std::isfinite(assumed_max_) ? "grid-unsafe" : "grid"; }
  std::uint64_t builds() const { return builds_; }

 private:
  int g_;
  double assumed_max_;
  int reach_ = 0;
  std::uint64_t builds_ = 0;
  CellIndex index_;
  std::vector<SpeedStats> slots_ = std::vector<SpeedStats>(1);
};

}  // namespace particle::detail
