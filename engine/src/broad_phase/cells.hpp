#pragma once
// Cells broad phase: O(N) per sub-step for slow or dense scenes, up to millions of particles.
//
// The cell side is chosen from the scene: at least s + 2 * cut (padded), where `cut` bounds the
// per-axis displacement of the "normal" particles, so every normal pair that can touch lies in
// adjacent cells (reach 1: a half stencil of 4.5 cells), and at least the side holding about one
// particle per cell, so spans are worth a vector loop. Particles are counting-sorted into cell
// order (CellIndex, CSR layout), so the stencil is two contiguous spans per particle.
//
// Cells kept across sub-steps (a skin): a sub-step checks every particle's drift and bins afresh
// only when too many particles have drifted out of reach of their cells. A binned
// particle's drift, per axis, is its distance from where the build saw it plus its displacement
// in this sub-step; while it is at most half of what the cell side leaves beside s (padded), no
// pair in cells two apart can collide, and a particle that drifts further is tested apart from
// then on, like an outlier (keep()). The rule reads the state of this sub-step, so it bounds what
// particles can do, however collisions changed their speeds. Where density sets the cell side
// (about one particle per cell), the side is well above s + 2 cut and slow particles keep their
// cells for several sub-steps: on the million-particle scene the counting sort, a third of the
// loop, ran every sub-step. With few particles per cell the pairs the kept cells can still bring
// into contact go into a list (broad_phase/pair_list.hpp), tested without walking the cells. A
// build also puts the World's particles back in the order of its cells once the order of the
// start has decayed (resort()), so a long run's scatter and list read the World in sequence.
//
// Fast outliers: a few fast particles must not inflate the cells for everyone. Particles faster
// than the cut are left out of the index and tested apart: each against the binned particles in
// the cells its reach box s + |u_f| + cut touches, and against the others apart whose swept
// intervals on x overlap its own. Still exact.
//
// The cut: twice the mean per-axis displacement when few particles (at most max(16, min(N/64,
// sqrt(8N))), so the outliers' pairwise tests stay O(N)) exceed it, else the largest displacement
// plus 1/16 (no outliers); then raised to whatever the chosen cell side allows. It is planned from
// the statistics the previous sub-step's binning or drift pass gathered (no extra pass);
// whatever the displacements are now, a particle above the cut in force is an outlier, so the plan
// only affects speed, never the pair set. Work split: dynamic chunks; the set never depends on it.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "broad_phase/cell_index.hpp"
#include "broad_phase/common.hpp"
#include "broad_phase/pair_list.hpp"
#include "parallel/team.hpp"
#include "step/float_pretest.hpp"
#include "step/stages.hpp"

namespace particle::detail {

struct CellsPlan {
  int n = 1;       // cells per side
  double cut = 0;  // per-axis displacement above which a particle is an outlier
};

// Particles per cell on average when density, not speed, sets the cell side: fewer, fuller cells
// mean less to clear and prefix-sum but longer spans (on the million-particle scene 2 was 5%
// slower).
inline constexpr double kParticlesPerCell = 1;

// How many particles may be tested apart (outliers): where their swept intervals all overlap
// (a column of them) they are tested against each other pairwise, so keep that O(N).
inline double outliers_allowed(std::size_t particles) {
  const double n = static_cast<double>(particles);
  return std::max(16.0, std::min(n / 64, std::sqrt(8 * n)));
}

// The largest per-axis drift d (broad_phase/cells.hpp, keep()) that two particles in cells of
// side `side`, two apart, can both have without a pair of them colliding: padded(s + 2 d) plus
// L * 2^-40 for the rounding of the drifts at most the side, shaved for this formula's own
// rounding. A particle moving at most d per axis in a sub-step is one, so it is also the largest
// cut the cells allow.
inline double drift_allowed(double side, double L, double s) {
  return ((side - 2 * L * 0x1p-40) / (1 + 0x1p-20) - s) / 2 * (1 - 0x1p-30);
}

// Pure: the grid for `particles` particles in [0, L]^2 given the displacement statistics (mean,
// max, and how many exceeded `probe`).
inline CellsPlan plan_cells(std::size_t particles, double L, double s, const SpeedStats& stats) {
  const double n_particles = static_cast<double>(particles);
  CellsPlan plan;
  if (stats.max <= stats.probe || static_cast<double>(stats.above) > outliers_allowed(particles))
    plan.cut = stats.max * (1 + 1.0 / 16);  // slack: a slightly faster particle stays normal
  else
    plan.cut = stats.probe;
  const double min_side = padded(s + 2 * plan.cut, L);
  // About kParticlesPerCell per cell: smaller cells only add empty spans.
  const double density_side = L / std::sqrt(std::max(1.0, n_particles / kParticlesPerCell));
  const double side = std::max(min_side, density_side);
  plan.n = static_cast<int>(std::clamp(std::floor(L / side), 1.0, 32768.0));
  while (plan.n > 1 && L / plan.n < min_side) --plan.n;
  // The cells are often wider than the cut needs (dense scenes): raise the cut to what they
  // allow, so fewer particles are outliers, at no cost.
  plan.cut = std::max(plan.cut, drift_allowed(L / plan.n, L, s));
  return plan;
}

// Cells a side up to which the wall candidates come from a pass over every particle, not from
// the border cells' (CellsBroadPhase::find_wall_candidates): 4 (n - 1) >= n^2 / 4.
inline constexpr int kWallPassSide = 15;

// Particles per cell up to which the kept cells' pairs go into a PairList: it holds about two
// pairs a particle for each particle a cell, 8 bytes a pair (on the million-particle scene, one
// particle a cell, 14 MB).
inline constexpr std::uint32_t kListedPerCell = 4;

// The share of binned particles whose successor in the cells' order lies more than two rows of
// cells away in the World (breaks) above which a build puts the World in the cells' order again
// (resort()). On the long run (N = 100,000 at the million scene's density, S = 2000) the breaks
// pass it at 60 of its 661 builds.
inline constexpr double kResortBreaks = 1.0 / 16;

// Particles above which the pair list's float records are stored past the caches
// (CellsBroadPhase::write_records8()): 4 MB of them. Measured: the slow crowd's 20,000 (640 kB)
// 5% slower streamed (loop at T = 2), N = 100,000 (1.6 MB) the same, a million (16 MB) 4% faster
// at T = 1 and 17% at T = 2 than stored through the caches.
inline constexpr std::size_t kStreamedRecords = std::size_t{1} << 18;

class CellsBroadPhase {
 public:
  void prepare(const World& w) {
    if (!built_) {
      build(w, false);
    } else {
      const bool recorded = listed_;  // keep() writes the records where the last build listed
      if (!keep(w)) build(w, recorded);
    }
    sort_apart(w);
  }

  // Pieces: the pair list's, or chunk_ binned particles each; then one per particle tested apart.
  std::uint32_t chunks(const World&) const { return binned_pieces() + tested_apart(); }

  // team, no barrier: the wall candidates of this sub-step, from the particles that can reach a
  // wall line alone. A binned particle stays within its drift of where the build saw it, and one
  // in a cell off the grid's border was at least a cell side c from each wall there; with a drift
  // d of at most (c - s) / 2 (drift_allowed(); at the build, the cut), it stays c - d >= c / 2 + r
  // from each wall, more than r: its centre cannot reach a wall line, by a margin far above any
  // rounding of its time. So the particles of the border cells are tested, and those apart.
  // Scanning every particle took a tenth of the slow crowd's loop. On a grid of up to
  // kWallPassSide cells a side, whose border holds a quarter of the cells or more, the
  // vectorized pass over every particle is the cheaper (the default scene's cells: 1% more
  // instructions through the border).
  void find_wall_candidates(const World& w, ThreadScratch& out) const {
    if (plan_.n <= kWallPassSide) {
      detail::find_wall_candidates(w, out);
      return;
    }
#pragma omp for schedule(static) nowait
    for (int row = 0; row < plan_.n; ++row)
      index_.for_border_of_row(row, [&](std::uint32_t begin, std::uint32_t end) {
        for (std::uint32_t k = begin; k < end; ++k)
          if (const std::uint32_t i = index_.id(k); apart_at_[i] == 0)
            detail::find_wall_candidate(w, i, out);
      });
    const std::uint32_t apart = tested_apart();
#pragma omp for schedule(static) nowait
    for (std::uint32_t a = 0; a < apart; ++a)
      detail::find_wall_candidate(w, apart_order_[a].slot, out);
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const std::uint32_t binned_chunks = binned_pieces();
    if (c < binned_chunks) {
      if (listed_) {
        pairs_.test_piece(c, w, records_.data(), pretest_ ? &*pretest_ : nullptr, apart_at_.data(),
                          out);
      } else {
        const std::uint32_t n = index_.binned();
        index_.test_half_stencils(c * chunk_, std::min(n, (c + 1) * chunk_), 1, w.s2, out);
      }
      return;
    }
    const auto a = static_cast<std::uint32_t>(c - binned_chunks);
    const ApartInterval& f = apart_order_[a];
    test_against_binned(w, f.slot, out);
    for (std::uint32_t b = a + 1; b < apart_order_.size() && apart_order_[b].start <= f.end; ++b) {
      test_pair(w, f.slot, apart_order_[b].slot, out);
      ++out.pair_tests;
    }
  }

  // A particle at slot f of w that the cells do not hold (tested apart, or a copy from elsewhere:
  // the mpi engine's halo) against every binned particle that can reach it. A binned particle is
  // at most its drift from its cell, counting its displacement now (keep()); L * 2^-40 for the
  // drift's rounding. On the World's values, pair by pair: the index's copy is refreshed only
  // where it is walked. Rare, so scalar.
  void test_against_binned(const World& w, std::uint32_t f, ThreadScratch& out) const {
    const RowParticle p = world_particle(w, f);
    index_.for_box(p.x, p.y, padded(w.s + std::fabs(p.ux) + reach_, w.L) + w.L * 0x1p-40,
                   padded(w.s + std::fabs(p.uy) + reach_, w.L) + w.L * 0x1p-40,
                   [&](std::uint32_t span_begin, std::uint32_t span_end) {
                     for (std::uint32_t k = span_begin; k < span_end; ++k) {
                       const std::uint32_t g = index_.id(k);
                       if (!apart_at_[g]) test_pair(w, f, g, out);
                     }
                     out.pair_tests += span_end - span_begin;
                   });
  }

  // The particles tested apart: the build's outliers, then those set apart since (some of which
  // may name a slot no particle holds now: slots_changed()).
  std::uint32_t apart() const {
    return static_cast<std::uint32_t>(outliers_.size() + drifted_.size());
  }
  std::uint32_t apart_particle(std::uint32_t a) const {
    const auto outliers = static_cast<std::uint32_t>(outliers_.size());
    return a < outliers ? outliers_[a] : drifted_[a - outliers];
  }

  // For the mpi engine's ranks (mpi/pair_search.hpp), whose own particles change slots between
  // sub-steps (mpi/exchange.hpp): one thread, before prepare(). `changed` are the slots that hold
  // another particle than in the last sub-step, `live` how many slots hold own particles now (the
  // World prepare() gets has n = live), `readable` how many slots the pair search may read (own
  // and halo: the arrays go that far). A changed slot is set apart, as a drifter is; a slot past
  // `live` holds no particle (kVacant) until a change fills it again. The cells are binned afresh
  // at the next prepare() when the last build's slots are no longer all readable.
  void slots_changed(std::span<const std::uint32_t> changed, std::uint32_t live,
                     std::uint32_t readable) {
    if (!built_) return;
    if (readable < built_slots_) {
      built_ = false;
      return;
    }
    if (apart_at_.size() < live) apart_at_.resize(live, 0);
#ifdef PARTICLE_FLOAT_PRETEST
    if (records_.size() < live) records_.resize(live);
#endif
    for (std::uint32_t v = live; v < std::min<std::size_t>(live_, apart_at_.size()); ++v)
      if (apart_at_[v] == 0) apart_at_[v] = kVacant;
    for (const std::uint32_t slot : changed) {
      if (slot >= live || apart_at_[slot] == 1) continue;
      apart_at_[slot] = 1;
      drifted_.push_back(slot);
    }
    live_ = live;
  }

  std::string name() const { return "cells"; }

  // How many times the particles were binned afresh (the other sub-steps kept the cells), and
  // how many particles drifted out of reach of their cells in between (tested apart).
  std::uint64_t builds() const { return builds_; }
  std::uint64_t drifted() const { return drifted_total_; }
  // How many builds put the World's particles in the order of their cells again (resort()).
  std::uint64_t resorts() const { return resorts_; }

 private:
  std::uint32_t binned_pieces() const {
    return listed_ ? pairs_.pieces() : (index_.binned() + chunk_ - 1) / chunk_;
  }

  // The particles apart that hold a slot (sort_apart()).
  std::uint32_t tested_apart() const { return static_cast<std::uint32_t>(apart_order_.size()); }

  // team, barrier at the end where any particle is apart (the same test on every thread; where
  // none is, start_apart() left the order empty): the particles apart that hold a slot
  // now (slots_changed()), in order of their swept intervals' starts on x, so that each is
  // tested against the later ones whose intervals overlap its own alone, as sweep does (the
  // others cannot touch it). Tested against each other pairwise, the million-particle scene's
  // 1,000 to 3,000 drifters before a build took 4 million tests, a tenth of its sub-steps'.
  void sort_apart(const World& w) {
    if (apart() == 0) return;
    team_single([&] {
      apart_order_.clear();
      for (std::uint32_t a = 0; a < apart(); ++a) {
        const std::uint32_t f = apart_particle(a);
        if (f < w.n)
          apart_order_.push_back(
              {swept_start(w.x[f], w.ux[f], w.r, w.L), swept_end(w.x[f], w.ux[f], w.r, w.L), f});
      }
      std::sort(apart_order_.begin(), apart_order_.end(),
                [](const ApartInterval& a, const ApartInterval& b) { return a.start < b.start; });
    });
  }

  // The static share of thread t among `threads` of `count` items: [first, second).
  static std::pair<std::uint32_t, std::uint32_t> share(std::uint32_t count, int t, int threads) {
    return {static_cast<std::uint32_t>(std::uint64_t(count) * t / threads),
            static_cast<std::uint32_t>(std::uint64_t(count) * (t + 1) / threads)};
  }

  // team, barrier at the end: checks every particle's drift, with the statistics for the next
  // plan, and says (the same on every thread) whether the cells of the last build still serve;
  // where they are walked (no pair list), brings the index's copy to this sub-step's values.
  //
  // A binned particle's drift is, per axis, its distance from where the build saw it plus its
  // displacement in this sub-step: what it can do, whatever collisions did to its speed. Two
  // particles in cells two apart on an axis were a cell side apart there at the build, and each
  // has since come closer by at most its drift less its displacement now: while both drifts are
  // at most drift_allowed(side), they are still more than s + |u_i| + |u_j| apart, and cannot
  // collide. A particle whose drift passes it leaves the index for the rest of the build
  // (apart_at_; a NaN in the copy, which no pre-test flags) and is tested apart, like an outlier,
  // against the index in a box widened by the largest drift left (reach_) and against the others
  // apart. The cells are binned afresh when more than outliers_allowed() would be apart, or when
  // the plan changes the grid. Cells of one or two per side hold every pair whatever the drift
  // (unless a pair list holds only those the bound lets collide): nobody drifts out of them.
  bool keep(const World& w) {
    const int t = omp_get_thread_num(), threads = omp_get_num_threads();
    SpeedStats mine;
    mine.probe = probe_;  // written by the previous sub-step, read before any change
    const std::size_t apart_before = apart();  // before the single below adds to it
    std::vector<std::uint32_t>& set_apart = apart_by_thread_[t];
    set_apart.clear();
    const auto [first, last] = share(static_cast<std::uint32_t>(w.n), t, threads);
    const double most = measure_drifts(w, first, last, mine, set_apart);
    slots_[t] = mine;
    drifts_[t] = most;
    team_barrier();
    SpeedStats all;
    // This sub-step's probe, read before the barrier: the single below writes the next one, and
    // a thread that read it from probe_ after another had done so planned other cells and could
    // decide otherwise whether to keep them (found as a hang of the mpi engine at P = 3, T = 2).
    all.probe = mine.probe;
    double reach = 0;
    std::size_t apart = apart_before;
    for (int u = 0; u < threads; ++u) {
      all.merge(slots_[u]);
      reach = std::max(reach, drifts_[u]);
      apart += apart_by_thread_[u].size();
    }
    const CellsPlan next = plan_cells(w.n, w.L, w.s, all);
    const bool kept = next.n == plan_.n && static_cast<double>(apart) <= outliers_allowed(w.n);
    if (kept && !listed_) {
      const auto [k_first, k_last] = share(index_.binned(), t, threads);
      index_.refresh(w, k_first, k_last,
                     [&](std::uint32_t k) { return apart_at_[index_.id(k)] == 0; });
    }
    team_single([&] {
      pending_ = next;
      probe_ = 2 * all.mean();
      reach_ = reach;
      plan_pretest(w, all.max);
      for (const auto& v : apart_by_thread_) drifted_.insert(drifted_.end(), v.begin(), v.end());
      drifted_total_ += apart - apart_before;
    });
    return kept;
  }

  // keep()'s pass over slots [first, last): adds their statistics to `mine`, sets apart (in
  // apart_at_ and `set_apart`) every binned particle whose drift passes drift_allowed_, and
  // returns the largest drift still binned.
  double measure_drifts(const World& w, std::uint32_t first, std::uint32_t last, SpeedStats& mine,
                        std::vector<std::uint32_t>& set_apart) {
    double most = 0;
    std::uint32_t i = measure_drifts_in_lanes(w, first, last, mine, set_apart, most);
    if (listed_) write_records(w, i, last);
    for (; i < last; ++i) {
      const double ux = w.ux[i], uy = w.uy[i];
      mine.add(ux, uy);
      if (apart_at_[i]) continue;
      const double drift = std::max(std::fabs(w.x[i] - built_x_[i]) + std::fabs(ux),
                                    std::fabs(w.y[i] - built_y_[i]) + std::fabs(uy));
      if (drift <= drift_allowed_) {
        most = std::max(most, drift);
      } else {
        apart_at_[i] = 1;
        set_apart.push_back(i);
      }
    }
    return most;
  }

  // measure_drifts() on whole registers of slots from `first` on, with AVX-512 or AVX2 (and
  // their records, where listed); `most` the largest drift still binned. Returns the first slot
  // it left to the scalar loop. Eight (four) particles at a time, a branch only where one drifts
  // out (rare): the statistics in SpeedLanes and the drift's test in masks. One lane at a time,
  // the loop was a tenth of the slow crowd's sub-steps. It reads every lane's build position, so
  // it stops at the slots the last build had (an mpi rank's slots past them hold particles set
  // apart since).
  std::uint32_t measure_drifts_in_lanes([[maybe_unused]] const World& w, std::uint32_t first,
                                        [[maybe_unused]] std::uint32_t last,
                                        [[maybe_unused]] SpeedStats& mine,
                                        [[maybe_unused]] std::vector<std::uint32_t>& set_apart,
                                        [[maybe_unused]] double& most) {
    std::uint32_t i = first;
#ifdef PARTICLE_FLOAT_PRETEST
    const auto built = static_cast<std::uint32_t>(std::min<std::size_t>(last, built_x_.size()));
    // Slots i + l for each bit l of `out`: drifted out.
    const auto set_apart_lanes = [&](unsigned out) {
      for (; out != 0; out &= out - 1) {
        const std::uint32_t j = i + static_cast<std::uint32_t>(__builtin_ctz(out));
        apart_at_[j] = 1;
        set_apart.push_back(j);
      }
    };
    SpeedLanes lanes(mine.probe);
#ifdef __AVX512F__
    if (i + 8 > built) return i;
    const __m512d allowed = _mm512_set1_pd(drift_allowed_);
    __m512d most8 = _mm512_setzero_pd();
    for (; i + 8 <= built; i += 8) {
      const __m512d ax = _mm512_abs_pd(_mm512_loadu_pd(w.ux + i));
      const __m512d ay = _mm512_abs_pd(_mm512_loadu_pd(w.uy + i));
      lanes.add(ax, ay);
      const __mmask8 binned = static_cast<__mmask8>(_mm_cmpeq_epi8_mask(
          _mm_loadl_epi64(reinterpret_cast<const __m128i*>(apart_at_.data() + i)),
          _mm_setzero_si128()));
      const __m512d bx = _mm512_cvtps_pd(_mm256_loadu_ps(built_x_.data() + i));
      const __m512d by = _mm512_cvtps_pd(_mm256_loadu_ps(built_y_.data() + i));
      const __m512d x = _mm512_loadu_pd(w.x + i), y = _mm512_loadu_pd(w.y + i);
      if (listed_) write_records8(i, x, y, _mm512_loadu_pd(w.ux + i), _mm512_loadu_pd(w.uy + i));
      const __m512d drift = _mm512_max_pd(_mm512_add_pd(_mm512_abs_pd(_mm512_sub_pd(x, bx)), ax),
                                          _mm512_add_pd(_mm512_abs_pd(_mm512_sub_pd(y, by)), ay));
      const __mmask8 within = _mm512_mask_cmp_pd_mask(binned, drift, allowed, _CMP_LE_OQ);
      most8 = _mm512_mask_max_pd(most8, within, most8, drift);
      set_apart_lanes(binned & ~within & 0xFFu);
    }
    most = _mm512_reduce_max_pd(most8);
#else
    if (i + 4 > built) return i;
    const __m256d allowed = _mm256_set1_pd(drift_allowed_);
    __m256d most4 = _mm256_setzero_pd();
    for (; i + 4 <= built; i += 4) {
      const __m256d ux = _mm256_loadu_pd(w.ux + i), uy = _mm256_loadu_pd(w.uy + i);
      const __m256d ax = abs_lanes(ux), ay = abs_lanes(uy);
      lanes.add(ax, ay);
      std::uint32_t flags;
      std::memcpy(&flags, apart_at_.data() + i, sizeof flags);
      const __m256d binned = _mm256_castsi256_pd(
          _mm256_cmpeq_epi64(_mm256_cvtepu8_epi64(_mm_cvtsi32_si128(static_cast<int>(flags))),
                             _mm256_setzero_si256()));
      const __m256d bx = _mm256_cvtps_pd(_mm_loadu_ps(built_x_.data() + i));
      const __m256d by = _mm256_cvtps_pd(_mm_loadu_ps(built_y_.data() + i));
      const __m256d x = _mm256_loadu_pd(w.x + i), y = _mm256_loadu_pd(w.y + i);
      if (listed_) write_records4(i, x, y, ux, uy);
      const __m256d drift = _mm256_max_pd(_mm256_add_pd(abs_lanes(_mm256_sub_pd(x, bx)), ax),
                                          _mm256_add_pd(abs_lanes(_mm256_sub_pd(y, by)), ay));
      const __m256d within = _mm256_and_pd(binned, _mm256_cmp_pd(drift, allowed, _CMP_LE_OQ));
      most4 = _mm256_max_pd(most4, _mm256_and_pd(within, drift));  // drifts are >= 0
      set_apart_lanes(static_cast<unsigned>(_mm256_movemask_pd(_mm256_andnot_pd(within, binned))));
    }
    alignas(32) double m[4];
    _mm256_store_pd(m, most4);
    most = std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
#endif
    lanes.add_to(mine, i - first);
#endif
    return i;
  }

  // team, barrier at the end: bins every particle afresh (the cells of pending_). `recorded`:
  // this sub-step's keep() has written every slot's record.
  void build(const World& w, bool recorded) {
    const int t = omp_get_thread_num();
    if (!planned_) {  // first sub-step: two passes for the statistics the plan needs
      const SpeedStats first = team_speed_stats(w, slots_);
      const SpeedStats second = team_speed_stats(w, slots_, 2 * first.mean());
      team_single([&] {
        pending_ = plan_cells(w.n, w.L, w.s, second);
        probe_ = 2 * first.mean();
        planned_ = true;
      });
    }
    SpeedStats mine;
    mine.probe = probe_;  // written by the previous sub-step's after(), read before any change
    index_.build(
        w, [&] { start_build(w); },
        [&](std::size_t lo, std::size_t hi, std::uint32_t* cells) {
          bin(w, lo, hi, cells, outliers_by_thread_[t]);
        },
        [&] {
          const auto [first, last] =
              share(static_cast<std::uint32_t>(w.n), t, omp_get_num_threads());
          add_speed_stats(w, first, last, mine);
          slots_[t] = mine;
        },
        [&] { finish_build(w); });
    const bool resorted = w.reorderable && resort(w);
    if (!listed_) return;
    // The records, unless keep() wrote them and no particle changed slot since (on the
    // million-particle scene the pass took 2 ms a build); the list's build ends in a barrier.
    if (!recorded || resorted) {
      const auto [first, last] = share(static_cast<std::uint32_t>(w.n), t, omp_get_num_threads());
      write_records(w, first, last);
    }
    // While the cells are kept, a pair of binned particles can collide only if it was within s
    // plus two drifts allowed, less than a cell side, on both axes here (the rounding of this
    // difference is far below the L * 2^-40 that drift_allowed() leaves).
    pairs_.build(index_, index_.cell_side());
  }

  // build()'s binning of slots [lo, hi) into `cells` (CellIndex::build()), particles faster than
  // the cut left out and added to `outliers` in slot order, with where the build sees each
  // particle (record_built(), in the pass that reads its position anyway: a pass of its own was 2
  // to 3 ns a particle on the million-particle scene). With AVX2 four particles a register, one
  // lane at a time only where one is an outlier (rare): one at a time, the pass was half of the
  // index's build on the slow crowd.
  void bin(const World& w, std::size_t lo, std::size_t hi, std::uint32_t* cells,
           std::vector<std::uint32_t>& outliers) {
    const double cut = plan_.cut;
    std::size_t i = lo;
#ifdef __AVX2__
    const __m256d fastest = _mm256_set1_pd(cut);
    for (; hi - i >= 4; i += 4) {
      const __m256d x = _mm256_loadu_pd(w.x + i), y = _mm256_loadu_pd(w.y + i);
      _mm_storeu_ps(built_x_.data() + i, _mm256_cvtpd_ps(x));
      _mm_storeu_ps(built_y_.data() + i, _mm256_cvtpd_ps(y));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(cells + i), index_.cells_of(x, y));
      const __m256d speed =
          _mm256_max_pd(abs_lanes(_mm256_loadu_pd(w.ux + i)), abs_lanes(_mm256_loadu_pd(w.uy + i)));
      for (auto out =
               static_cast<unsigned>(_mm256_movemask_pd(_mm256_cmp_pd(speed, fastest, _CMP_GT_OQ)));
           out != 0; out &= out - 1) {
        const std::size_t j = i + static_cast<unsigned>(__builtin_ctz(out));
        cells[j] = CellIndex::kNotBinned;
        outliers.push_back(static_cast<std::uint32_t>(j));
      }
    }
#endif
    for (; i < hi; ++i) {
      record_built(w, i);
      if (axis_speed(w, i) > cut) {
        cells[i] = CellIndex::kNotBinned;
        outliers.push_back(static_cast<std::uint32_t>(i));
      } else {
        cells[i] = index_.cell_of(w.x[i], w.y[i]);
      }
    }
  }

  // The listed pairs' float pre-test for this sub-step, where it applies (AVX-512 or AVX2, floats
  // that hold the scene's squares): every velocity component at most `fastest`, every position
  // in [0, L] (docs/model.md).
  void plan_pretest(const World& w, double fastest) {
    if (listed_ && FloatPretest::applies(w.s, w.L, fastest))
      pretest_.emplace(w.s, w.L, fastest);
    else
      pretest_.reset();
  }

  // The float records of slots [first, last), for the listed pairs' float pre-test; written
  // where the list is, with AVX-512 or AVX2 (elsewhere the pre-test runs in double on the World).
  void write_records([[maybe_unused]] const World& w, [[maybe_unused]] std::uint32_t first,
                     [[maybe_unused]] std::uint32_t last) {
#ifdef PARTICLE_FLOAT_PRETEST
    std::uint32_t i = first;
#ifdef __AVX512F__
    for (; last - i >= 8; i += 8)
      write_records8(i, _mm512_loadu_pd(w.x + i), _mm512_loadu_pd(w.y + i),
                     _mm512_loadu_pd(w.ux + i), _mm512_loadu_pd(w.uy + i));
#else
    for (; last - i >= 4; i += 4)
      write_records4(i, _mm256_loadu_pd(w.x + i), _mm256_loadu_pd(w.y + i),
                     _mm256_loadu_pd(w.ux + i), _mm256_loadu_pd(w.uy + i));
#endif
    for (; i < last; ++i)
      records_[i] = {static_cast<float>(w.x[i]), static_cast<float>(w.y[i]),
                     static_cast<float>(w.ux[i]), static_cast<float>(w.uy[i])};
    _mm_sfence();  // the streamed stores, before the barrier that lets the search read them
#endif
  }

#ifdef __AVX512F__
  // Slots i to i + 7 from their values: four conversions to float and a transpose. Where the
  // records pass kStreamedRecords they are stored past the caches (non-temporal): on the
  // million-particle scene (16 MB of records) a store that first read its line back cost more
  // than the search gained from finding some in the cache (loop 236 against 195 ms at T = 2);
  // the slow crowd's 640 kB are read back from the cache.
  void write_records8(std::uint32_t i, __m512d x, __m512d y, __m512d ux, __m512d uy) {
    const __m256 fx = _mm512_cvtpd_ps(x), fy = _mm512_cvtpd_ps(y);
    const __m256 fu = _mm512_cvtpd_ps(ux), fv = _mm512_cvtpd_ps(uy);
    // {x0 y0 x1 y1 | x4 y4 x5 y5}, {x2 y2 x3 y3 | x6 y6 x7 y7}, and the same of the velocities.
    const __m256d xy_lo = _mm256_castps_pd(_mm256_unpacklo_ps(fx, fy));
    const __m256d xy_hi = _mm256_castps_pd(_mm256_unpackhi_ps(fx, fy));
    const __m256d u_lo = _mm256_castps_pd(_mm256_unpacklo_ps(fu, fv));
    const __m256d u_hi = _mm256_castps_pd(_mm256_unpackhi_ps(fu, fv));
    // Records {0 | 4}, {1 | 5}, {2 | 6}, {3 | 7}: 16 bytes each, on a 16-byte boundary.
    const __m256d r[4] = {_mm256_unpacklo_pd(xy_lo, u_lo), _mm256_unpackhi_pd(xy_lo, u_lo),
                          _mm256_unpacklo_pd(xy_hi, u_hi), _mm256_unpackhi_pd(xy_hi, u_hi)};
    auto* out = reinterpret_cast<double*>(records_.data() + i);
    for (int k = 0; k < 4; ++k) {
      const __m128d low = _mm256_castpd256_pd128(r[k]), high = _mm256_extractf128_pd(r[k], 1);
      if (streamed_) {
        _mm_stream_pd(out + 2 * k, low);
        _mm_stream_pd(out + 2 * k + 8, high);
      } else {
        _mm_store_pd(out + 2 * k, low);
        _mm_store_pd(out + 2 * k + 8, high);
      }
    }
  }
#elif defined(PARTICLE_FLOAT_PRETEST)
  // write_records8 on slots i to i + 3 (AVX2): four conversions and a 4 x 4 transpose.
  void write_records4(std::uint32_t i, __m256d x, __m256d y, __m256d ux, __m256d uy) {
    __m128 r0 = _mm256_cvtpd_ps(x), r1 = _mm256_cvtpd_ps(y);
    __m128 r2 = _mm256_cvtpd_ps(ux), r3 = _mm256_cvtpd_ps(uy);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    float* out = &records_[i].x;
    if (streamed_) {
      _mm_stream_ps(out, r0);
      _mm_stream_ps(out + 4, r1);
      _mm_stream_ps(out + 8, r2);
      _mm_stream_ps(out + 12, r3);
    } else {
      _mm_store_ps(out, r0);
      _mm_store_ps(out + 4, r1);
      _mm_store_ps(out + 8, r2);
      _mm_store_ps(out + 12, r3);
    }
  }
#endif

  // Where particle i (a slot) was at the last build, for keep()'s drifts.
  void record_built(const World& w, std::size_t i) {
    built_x_[i] = static_cast<float>(w.x[i]);
    built_y_[i] = static_cast<float>(w.y[i]);
  }

  // build()'s first step, on one thread: the grid of pending_ and the team's slots.
  void start_build(const World& w) {
    plan_ = pending_;
    index_.set_grid(plan_.n, w.L);
    // Where even every particle binned would be listed (finish_build()), the copy's velocities
    // are never read: the list, keep() and the particles apart read the World's.
    index_.copy_velocities(w.n > kListedPerCell * index_.cells());
    built_x_.resize(w.n);
    built_y_.resize(w.n);
#ifdef PARTICLE_FLOAT_PRETEST
    records_.resize(w.n);
    streamed_ = w.n > kStreamedRecords;
#endif
    SpeedStats fresh;
    fresh.probe = probe_;
    const int threads = omp_get_num_threads();
    slots_.assign(threads, fresh);
    drifts_.resize(threads);
    breaks_.resize(threads);
    apart_by_thread_.resize(threads);
    outliers_by_thread_.resize(threads);
    for (auto& v : outliers_by_thread_) v.clear();
  }

  // build()'s last step, on one thread once every particle is binned: the outliers, the next
  // plan, and what keep() needs.
  void finish_build(const World& w) {
    outliers_.clear();
    for (const auto& v : outliers_by_thread_) outliers_.insert(outliers_.end(), v.begin(), v.end());
    SpeedStats all;
    all.probe = probe_;
    for (const SpeedStats& s : slots_) all.merge(s);
    pending_ = plan_cells(w.n, w.L, w.s, all);
    probe_ = 2 * all.mean();
    const int threads = omp_get_num_threads();
    chunk_ = std::max<std::uint32_t>(16, index_.binned() / (64 * threads));
    reach_ = plan_.cut;  // no drift yet: binned particles move at most the cut
    start_apart(static_cast<std::uint32_t>(w.n));
    listed_ = index_.binned() <= kListedPerCell * index_.cells();
    plan_pretest(w, all.max);
    // The build's positions are kept as floats, within 2^-24 L of the doubles (the engine's unit
    // puts L far above float's smallest normal; past its largest they are infinite and every
    // particle drifts): the drift allowed is that much less.
    drift_allowed_ = !listed_ && index_.cells() <= 4
                         ? INFINITY
                         : drift_allowed(index_.cell_side(), w.L, w.s) - w.L * 0x1p-23;
    built_ = true;
    ++builds_;
  }

  // After a build of n slots: the outliers alone are apart, every slot holds its particle.
  void start_apart(std::uint32_t n) {
    apart_at_.assign(n, 0);
    for (const std::uint32_t f : outliers_) apart_at_[f] = 1;
    drifted_.clear();
    apart_order_.clear();
    built_slots_ = live_ = n;
  }

  // team, after a build: puts the World's particles in the order of the cells just built (the
  // binned ones in the index's order, then the outliers) when the World's order has drifted too
  // far from it. The measure is the index's breaks, positions whose successor lies more than two
  // rows of cells away in the World: the reach of a half stencil, within which a particle that
  // changed cell since the last re-sort still sits (a build is due after a quarter of a cell's
  // drift, so counting every successor that is not the next slot would re-sort at every build).
  // Each break is a write far out of sequence in the next build's scatter and, in every sub-step,
  // a pair whose particles lie far apart in the World. The breaks grow with the distance the
  // particles have travelled, not with time: slow scenes re-sort rarely (the million scene's 20
  // time units reach 2%), and a scene whose cells are coarser than the start's grid re-sorts at
  // its first build. The decision reads the index alone, so it is the same for every thread
  // count; the order changes which slot holds a particle, never the result (the stages break
  // ties and orient pairs by id).
  // Returns whether it did (the same on every thread).
  bool resort(const World& w) {
    const int t = omp_get_thread_num(), threads = omp_get_num_threads();
    const std::uint32_t binned = index_.binned();
    const auto [first, last] = share(binned, t, threads);
    std::uint32_t breaks = 0;
    const std::uint32_t near = 2 * binned / static_cast<std::uint32_t>(plan_.n) + 1;  // two rows
    for (std::uint32_t k = first; k < last; ++k)  // |id(k + 1) - id(k)| > near, modulo 2^32
      breaks += k + 1 < binned && index_.id(k + 1) - index_.id(k) + near > 2 * near;
    breaks_[t] = breaks;
    team_barrier();
    std::uint64_t all = 0;
    for (int u = 0; u < threads; ++u) all += breaks_[u];
    if (static_cast<double>(all) <= kResortBreaks * binned) return false;
    const auto n = static_cast<std::uint32_t>(w.n);
    team_single([&] {
      from_.resize(n);
      moved_.resize(n);
      ++resorts_;
    });
    // Not a structured binding: the lambda below captures them, which Clang 14 (make fuzz) refuses.
    const std::pair<std::uint32_t, std::uint32_t> slots = share(n, t, threads);
    const std::uint32_t i_first = slots.first, i_last = slots.second;
    for (std::uint32_t i = i_first; i < i_last; ++i)
      from_[i] = i < binned ? index_.id(i) : outliers_[i - binned];
    // Each array through moved_: a gather by slot, then, once every thread has read the old
    // order, the copy back.
    const auto move = [&](auto* a) {
      using T = std::remove_pointer_t<decltype(a)>;
      for (std::uint32_t i = i_first; i < i_last; ++i) {
        if constexpr (sizeof(T) == sizeof(std::uint64_t))
          moved_[i] = std::bit_cast<std::uint64_t>(a[from_[i]]);
        else
          moved_[i] = a[from_[i]];
      }
      team_barrier();
      for (std::uint32_t i = i_first; i < i_last; ++i) {
        if constexpr (sizeof(T) == sizeof(std::uint64_t))
          a[i] = std::bit_cast<T>(moved_[i]);
        else
          a[i] = static_cast<T>(moved_[i]);
      }
      team_barrier();
    };
    for_each_particle_array(w, move);
    move(w.id);
    index_.renumber(first, last);
    for (std::uint32_t i = i_first; i < i_last; ++i) record_built(w, i);  // in the new slots
    team_single([&] {
      for (std::size_t j = 0; j < outliers_.size(); ++j)
        outliers_[j] = binned + static_cast<std::uint32_t>(j);
      std::fill(apart_at_.begin(), apart_at_.begin() + binned, 0);
      std::fill(apart_at_.begin() + binned, apart_at_.end(), 1);
    });
    return true;
  }

  bool planned_ = false;
  bool built_ = false;
  bool listed_ = false;  // the kept cells' pairs are in pairs_ (few particles per cell)
  std::uint64_t builds_ = 0, drifted_total_ = 0, resorts_ = 0;
  double reach_ = 0;  // the largest drift of a binned particle (per axis): the outliers' margin
  CellsPlan plan_, pending_;
  double probe_ = INFINITY;
  std::uint32_t chunk_ = 16;
  CellIndex index_;
  std::vector<SpeedStats> slots_ = std::vector<SpeedStats>(1);
  std::vector<double> drifts_;         // per thread: the largest drift still binned
  std::vector<std::uint32_t> breaks_;  // per thread: its share of the index's breaks (resort())
  std::vector<std::uint32_t> from_;    // resort(): the slot each slot's particle comes from
  std::vector<std::uint64_t> moved_;   // resort(): one array in its new order
  double drift_allowed_ = 0;  // drift_allowed() of the cells, or infinite (one or two a side)
  // By slot: 0 binned, 1 tested apart (an outlier, or set apart since the build), kVacant a slot
  // that held a binned particle and holds none now (slots_changed()).
  static constexpr std::uint8_t kVacant = 2;
  std::vector<std::uint8_t> apart_at_;
  std::uint32_t built_slots_ = 0, live_ = 0;  // the World's n at the last build, and now
  std::vector<std::uint32_t> drifted_;        // those set apart since, in thread order
  struct ApartInterval {
    double start, end;  // the swept interval on x
    std::uint32_t slot;
  };
  std::vector<ApartInterval> apart_order_;  // sort_apart()
  std::vector<std::vector<std::uint32_t>> apart_by_thread_;
  Uninitialized<float> built_x_, built_y_;  // by slot: each particle at the build
  LineAligned<FloatParticle> records_;      // by slot: its values now, as floats (write_records())
  std::optional<FloatSubStepPretest> pretest_;  // the list's float pre-test (plan_pretest())
#ifdef PARTICLE_FLOAT_PRETEST
  bool streamed_ = false;  // the records are stored non-temporally
#endif
  PairList pairs_;
  std::vector<std::vector<std::uint32_t>> outliers_by_thread_;
  std::vector<std::uint32_t> outliers_;  // ids, in thread order (the set is what matters)
};

}  // namespace particle::detail
