#pragma once
// Auto broad phase: runs whichever of brute, sweep, bands and cells is cheapest for the scene,
// re-checked every kRecheck sub-steps as speeds change (collisions spread them). All four find
// brute's candidate set, so switching never changes the result, only the time.
//
// Cost model, in pair tests per sub-step (one pair test ~ 0.5-0.7 ns here), from N, the density
// and the displacement statistics (two O(N) passes per check, amortized over kRecheck sub-steps):
//   brute  N^2 / 2
//   sweep  f N^2 / 2 + 16 N, f = 2H - H^2 the chance that two swept x intervals of mean width
//          H L = mean|ux| + 2r overlap, for uniform positions
//   bands  sweep's pairs times g + (1 - g) min(1, 1.4 / B), g the same chance on y, + 20 N
//          (placing and copying) + 40 N (1 + B H_y) (the entries: sorting, copying, a span
//          each; broad_phase/bands.hpp), B as bands plans it
//   cells  N * 4.5 (cells of the half stencil) * particles per cell + 24 N (binning) + for each
//          outlier its reach box and the other outliers
// The constants were fitted from bench_engine's BM_BroadAndNarrow runs on the scenes,
// bands's from psim runs (docs/performance.md, "bands").
// name() is "auto:" plus the engines it ran, in order of first use, e.g. "auto:sweep" or
// "auto:cells+sweep".
#include <string>
#include <vector>

#include "broad_phase/bands.hpp"
#include "broad_phase/brute.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/common.hpp"
#include "broad_phase/sweep.hpp"
#include "parallel/team.hpp"

namespace particle::detail {

enum class AutoChoice { brute, sweep, bands, cells };

struct AutoCosts {
  double brute, sweep, bands, cells;
};

// The chance that two swept intervals of mean width H L overlap, for uniform positions.
inline double overlap_chance(double H) { return H >= 1 ? 1 : 2 * H - H * H; }

// Pure: the estimated cost of each engine per sub-step. `stats` must have probe = 2 * its mean.
inline AutoCosts estimate_costs(std::size_t particles, double L, double r,
                                const SpeedStats& stats) {
  const double n = static_cast<double>(particles), s = 2 * r;
  const double all_pairs = n * (n - 1) / 2;
  AutoCosts cost{};
  cost.brute = all_pairs;

  const PathSums sums = path_sums(particles, s, stats);
  const double x_pairs = overlap_chance(sums.width / std::max(1.0, n) / L) * all_pairs;
  cost.sweep = x_pairs + 16 * n;

  const double height = sums.height / std::max(1.0, n) / L, y_overlap = overlap_chance(height);
  const double bands = plan_bands(particles, L, sums);
  cost.bands = x_pairs * (y_overlap + (1 - y_overlap) * std::min(1.0, 1.4 / bands)) +
               kBandsParticleCost * n + kBandsEntryCost * n * (1 + bands * std::min(1.0, height));

  const CellsPlan plan = plan_cells(particles, L, s, stats);
  const double side = L / plan.n;
  const double outliers = plan.cut < stats.max ? static_cast<double>(stats.above) : 0;
  const double binned = n - outliers;
  const double per_cell = binned / (static_cast<double>(plan.n) * plan.n);
  const double stencil = plan.n == 1 ? 0.5 * binned : 4.5 * per_cell;
  const double reach = std::min(L, 2 * (s + stats.max + plan.cut) + side);
  const double box = std::min(binned, binned * reach * reach / (L * L));
  cost.cells = binned * stencil + 24 * n + outliers * (box + outliers / 2 + 8);
  return cost;
}

inline AutoChoice cheapest(const AutoCosts& c) {
  if (c.cells <= c.sweep && c.cells <= c.bands && c.cells <= c.brute) return AutoChoice::cells;
  if (c.bands < c.sweep && c.bands <= c.brute) return AutoChoice::bands;
  if (c.sweep <= c.brute) return AutoChoice::sweep;
  return AutoChoice::brute;
}

class AutoBroadPhase {
 public:
  static constexpr int kRecheck = 32;

  void prepare(const World& w) {
    // Each thread counts its own sub-steps: a shared counter would need a barrier between its
    // update and every thread's read.
    fit_to_team(substeps_);
    if (substeps_[static_cast<std::size_t>(omp_get_thread_num())]++ % kRecheck == 0) {
      const SpeedStats first = team_speed_stats(w, slots_);
      const SpeedStats stats = team_speed_stats(w, slots_, 2 * first.mean());
      team_single([&] {
        choice_ = cheapest(estimate_costs(w.n, w.L, w.r, stats));
        bool seen = false;
        for (AutoChoice c : used_) seen |= c == choice_;
        if (!seen) used_.push_back(choice_);
      });
    }
    switch (choice_) {
      case AutoChoice::brute:
        brute_.prepare(w);
        break;
      case AutoChoice::sweep:
        sweep_.prepare(w);
        break;
      case AutoChoice::bands:
        bands_.prepare(w);
        break;
      case AutoChoice::cells:
        cells_.prepare(w);
        break;
    }
  }

  std::uint32_t chunks(const World& w) const {
    switch (choice_) {
      case AutoChoice::brute:
        return brute_.chunks(w);
      case AutoChoice::sweep:
        return sweep_.chunks(w);
      case AutoChoice::bands:
        return bands_.chunks(w);
      case AutoChoice::cells:
        return cells_.chunks(w);
    }
    return 0;
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    switch (choice_) {
      case AutoChoice::brute:
        brute_.find_pairs_in(w, c, out);
        break;
      case AutoChoice::sweep:
        sweep_.find_pairs_in(w, c, out);
        break;
      case AutoChoice::bands:
        bands_.find_pairs_in(w, c, out);
        break;
      case AutoChoice::cells:
        cells_.find_pairs_in(w, c, out);
        break;
    }
  }

  // team, no barrier: the cells' wall candidates where they run, else every particle's.
  void find_wall_candidates(const World& w, ThreadScratch& out) const {
    if (choice_ == AutoChoice::cells)
      cells_.find_wall_candidates(w, out);
    else
      detail::find_wall_candidates(w, out);
  }

  std::string name() const {
    std::string text = "auto:";
    for (std::size_t k = 0; k < used_.size(); ++k) {
      if (k) text += '+';
      text += used_[k] == AutoChoice::brute   ? "brute"
              : used_[k] == AutoChoice::sweep ? "sweep"
              : used_[k] == AutoChoice::bands ? "bands"
                                              : "cells";
    }
    return text;
  }

  std::uint64_t builds() const {
    return brute_.builds() + sweep_.builds() + bands_.builds() + cells_.builds();
  }

 private:
  AutoChoice choice_ = AutoChoice::brute;
  std::vector<AutoChoice> used_;
  std::vector<long> substeps_;  // per thread
  std::vector<SpeedStats> slots_ = std::vector<SpeedStats>(1);
  BruteBroadPhase brute_;
  SweepBroadPhase sweep_;
  BandsBroadPhase bands_;
  CellsBroadPhase cells_;
};

}  // namespace particle::detail
