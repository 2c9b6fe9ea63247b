#pragma once
// One rank's pair search: every pair with an own particle that may collide in this sub-step,
// each tested once on this rank. The own particles (slots [0, owned)) go into the cells engine's
// broad phase (broad_phase/cells.hpp), kept across sub-steps as there: binned afresh only when
// too many have drifted out of reach of their cells. The exchange between sub-steps moves
// particles between slots (mpi/exchange.hpp); the slots it changed are set apart, as drifters are
// (CellsBroadPhase::slots_changed). Each halo particle is tested against the binned own particles
// in its reach box, as the cells engine tests a particle apart, and against the own particles
// tested apart that lie near the slab's edges. Halo pairs are never tested: their owners test
// them.
//
// Exact for any speed: the cells' argument (docs/engines.md, "Cells kept across sub-steps") holds
// for the own pairs whatever the slots; a halo particle h and an own particle f can touch only if
// |x_f - x_h| <= s + |u_xf| + |u_xh|, at most the halo's reach, and h lies outside the slab
// [lo, hi), so f lies within the reach of an edge (twice the reach is taken, which leaves the
// rounding of these sums far behind). The same tests, on the same bits, as the other engines run:
// the candidates are brute's.
//
// An own-halo pair is tested here and on the halo particle's owner: those tests go to `cross`,
// so that the run counts each overlap once (half the sum over ranks) and each test where it
// was made.
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "broad_phase/cells.hpp"
#include "mpi/slabs.hpp"
#include "parallel/team.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail::mpi {

class PairSearch {
 public:
  // Halo particles per piece.
  static constexpr std::uint32_t kHaloChunk = 16;

  // One thread, before the team: `owned` own particles now in slots [0, owned), after the
  // exchange changed the slots `changed`; `halo` halo particles after them; the slab [lo, hi) and
  // the halo's reach.
  void plan(std::size_t owned, std::size_t halo, std::span<const std::uint32_t> changed,
            Slabs::Interval slab, double reach) {
    owned_ = static_cast<std::uint32_t>(owned);
    halo_ = static_cast<std::uint32_t>(halo);
    near_lo_ = slab.lo + 2 * reach;
    near_hi_ = slab.hi - 2 * reach;
    cells_.slots_changed(changed, owned_, owned_ + halo_);
  }

  // team, barrier at the end: the cells of the own particles (own: the World of slots
  // [0, owned)), and the own particles apart near the slab's edges.
  void prepare(const World& own) {
    cells_.prepare(own);
    team_single([&] {
      near_.clear();
      for (std::uint32_t a = 0; a < cells_.apart(); ++a) {
        const std::uint32_t f = cells_.apart_particle(a);
        if (f < owned_ && (own.x[f] <= near_lo_ || own.x[f] >= near_hi_)) near_.push_back(f);
      }
    });
  }

  // team, no barrier, after prepare: the own particles' wall candidates, from those the cells
  // say can reach a wall line (CellsBroadPhase::find_wall_candidates).
  void find_wall_candidates(const World& own, ThreadScratch& out) const {
    cells_.find_wall_candidates(own, out);
  }

  // Pieces: the cells', then kHaloChunk halo particles each.
  std::uint32_t chunks(const World& own) const {
    return cells_.chunks(own) + (halo_ + kHaloChunk - 1) / kHaloChunk;
  }

  // any thread, after prepare: the pairs of piece c. w holds every slot, own then halo; own its
  // first owned.
  void find_pairs_in(const World& w, const World& own, std::uint32_t c, ThreadScratch& mine,
                     ThreadScratch& cross) const {
    const std::uint32_t own_chunks = cells_.chunks(own);
    if (c < own_chunks) {
      cells_.find_pairs_in(own, c, mine);
      return;
    }
    const std::uint32_t first = owned_ + (c - own_chunks) * kHaloChunk;
    for (std::uint32_t h = first; h < std::min(owned_ + halo_, first + kHaloChunk); ++h) {
      cells_.test_against_binned(w, h, cross);
      for (const std::uint32_t f : near_) test_pair(w, f, h, cross);
      cross.pair_tests += near_.size();
    }
  }

  // How many times the own particles were binned afresh.
  std::uint64_t builds() const { return cells_.builds(); }

 private:
  CellsBroadPhase cells_;
  std::uint32_t owned_ = 0, halo_ = 0;
  double near_lo_ = 0, near_hi_ = 0;  // own particles at most near_lo_ or at least near_hi_
  std::vector<std::uint32_t> near_;   // the own particles apart near the slab's edges
};

}  // namespace particle::detail::mpi
