#pragma once
// One rank's pair search: every pair with an own particle that may collide in this sub-step,
// each tested once on this rank. The own particles go into a cell index (the cells engine's
// CellIndex, cells planned by its plan_cells with no outliers): own pairs over their half
// stencils; each halo particle against the own particles in its reach box, as the cells engine
// tests a fast outlier. Halo pairs are never tested: their owners test them.
//
// Exact for any speed: the cells are at least s + 2 cut wide (padded), with cut above every own
// particle's per-axis displacement, so every own pair that can touch lies in adjacent cells; a
// halo particle's box reaches s + |u| + cut per axis (padded). The same tests, on the same bits,
// as the other engines run: the candidates are brute's.
//
// An own-halo pair is tested here and on the halo particle's owner: those tests go to `cross`,
// so that the run counts each overlap once (half the sum over ranks) and each test where it
// was made.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "broad_phase/cell_index.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/common.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail::mpi {

class PairSearch {
 public:
  // Halo particles per piece.
  static constexpr std::uint32_t kHaloChunk = 16;

  // One thread, before the team: the cells for `owned` own particles whose largest per-axis
  // displacement is `largest`, and the pieces for `halo` halo particles and `threads` threads.
  void plan(std::size_t owned, std::size_t halo, double L, double s, double largest, int threads) {
    SpeedStats stats;
    stats.max = largest;  // probe stays infinite: no outliers, every own particle binned
    plan_ = plan_cells(owned, L, s, stats);
    owned_ = static_cast<std::uint32_t>(owned);
    halo_ = static_cast<std::uint32_t>(halo);
    chunk_ = std::max<std::uint32_t>(16, owned_ / (64 * static_cast<std::uint32_t>(threads)));
  }

  // team, barrier at the end: the cell index of the own particles, slots [0, own.n).
  void prepare(const World& own) {
    index_.build(
        own, [&] { index_.set_grid(plan_.n, own.L); },
        [&](std::size_t i) { return index_.cell_of(own.x[i], own.y[i]); }, [] {}, [] {});
  }

  // Pieces: chunk_ own particles each, then kHaloChunk halo particles each.
  std::uint32_t chunks() const { return own_chunks() + (halo_ + kHaloChunk - 1) / kHaloChunk; }

  // any thread, after prepare: the pairs of piece c. w holds every slot, own then halo.
  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& own,
                     ThreadScratch& cross) const {
    if (c < own_chunks()) {
      index_.test_half_stencils(c * chunk_, std::min(owned_, (c + 1) * chunk_), 1, w.s2, own);
      return;
    }
    const std::uint32_t first = owned_ + (c - own_chunks()) * kHaloChunk;
    for (std::uint32_t h = first; h < std::min(owned_ + halo_, first + kHaloChunk); ++h) {
      const RowParticle p = world_particle(w, h);
      index_.test_box(p, padded(w.s + std::fabs(p.ux) + plan_.cut, w.L),
                      padded(w.s + std::fabs(p.uy) + plan_.cut, w.L), w.s2, cross);
    }
  }

 private:
  std::uint32_t own_chunks() const { return (owned_ + chunk_ - 1) / chunk_; }

  CellsPlan plan_;
  std::uint32_t owned_ = 0, halo_ = 0, chunk_ = 16;
  CellIndex index_;
};

}  // namespace particle::detail::mpi
