#pragma once
// Bands broad phase: sort-and-sweep inside horizontal bands, for long paths (the default scene
// moves up to a quarter of the box per step). Sweep keeps every pair whose swept x intervals
// overlap, about five times the pairs whose swept boxes overlap on both axes there; bands keeps
// about 1.4 / B of the difference, B the band count, for about N B H more entries (H the mean
// swept y interval over L).
//
// Each particle's swept box is sweep's interval on each axis, [min(x, x + ux) - r,
// max(x, x + ux) + r] padded (broad_phase/common.hpp): the straight path of the narrow phase
// over the whole sub-step, including the part past a wall line (a pair that meets there is a
// candidate of the model, docs/model.md step 2, and counts in pair_candidates). Two disks can
// only touch, or overlap at the start, if their boxes overlap on both axes.
//
// The y range is cut into B bands; a particle has an entry in every band its y interval meets:
// a *starter* in the band of its interval's start, a *passer* in the later ones. A pair whose y
// intervals overlap is owned by the band of the larger of the two starts: both intervals contain
// that start, so both have an entry there, and the one that starts later is a starter. A band
// tests its starter-starter and starter-passer pairs, never passer-passer ones, so each pair is
// tested in one band at most. Inside a band the entries are in bucket order of x start (sweep's
// counting sort, X buckets over [0, L], bucket_of monotone), in each bucket its
// passers before its starters; the starters are also copied alone, in the same order. Each entry
// owns one span, and each pair whose x intervals overlap is in one span:
//   starter k: positions k+1 .. the end of the bucket of k's x end (sweep's span), starters and
//     passers;
//   passer q: the starters' copy, buckets bucket(start_q) .. bucket(end_q).
// A starter's span holds the passer q exactly when bucket(start_q) > bucket(start_k) (a passer
// of k's own bucket comes before k), the passer's holds k exactly when bucket(start_k) >=
// bucket(start_q): one of the two (docs/engines.md, "bands").
//
// Bands and buckets cover [0, L], the ends clamped: every interval that starts below 0 contains
// [0, r] (it holds its particle, at x >= r), so all of them overlap one another, and those that end
// past L likewise; clamping them into the first or last bucket adds no pair that does not
// overlap on that axis.
//
// Time slices. Boxes of whole paths cannot go below the pairs whose boxes overlap on both axes
// (about 1,130 tests per pair that meets on the default scene). So the sub-step is cut into K
// slices (K a power of 2, planned with B) and each particle's path into K pieces, piece p the
// straight path over t in [p, p + 1] / K: a particle at x + ux p / K moving ux / K, whose box is
// built as above. Two disks that touch at a time t in slice p have overlapping piece-p boxes (on
// each axis both centres at t lie inside their pieces' intervals, which reach r past them), so
// a pair that meets is tested in the slice of its time; it may be tested in other slices too,
// and each test keeps only what belongs to its own slice (step/narrow_phase.hpp, TimeSlice):
// the candidate whose time, the same bits in every slice, is in it, and the overlaps at t = 0 in
// slice 0. Piece boxes are padded as whole ones: the rounding of x + ux p / K (one product, p /
// K exact) is far inside the padding, and a candidate's rounded time t leaves the pair within s
// (1 + 2^-23) or so of touching at t (contact.hpp's terms: a few ulps of |d| |w| on the square),
// inside the relative 2^-20 of each piece's reach. Pairs of boxes that overlap fall as 1 / K (a
// piece's box is 1 / K of the path's on each axis, and there are K slices); the entries' starts
// grow as K N.
//
// Cost per sub-step: O(K N + N B H) entries by a counting sort, plus the pairs of the spans, one
// span per entry as sweep has one per particle (an entry costs about 40 pair tests on the
// default scene: a second span per starter cost more than the bands saved). The candidate set
// is brute's, so the order of the tests does not matter.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "broad_phase/common.hpp"
#include "parallel/private_state.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail {

// The swept intervals' lengths, summed over the particles: what plans the bands.
struct PathSums {
  double width = 0, height = 0;
};

// From the displacement statistics of n particles of contact distance s (auto's, or bands' own),
// of the pieces of one of `slices` time slices.
inline PathSums path_sums(std::size_t n, double s, const SpeedStats& stats,
                          std::uint32_t slices = 1) {
  const double contact = static_cast<double>(n) * s;
  return {stats.sum_abs_ux / slices + contact, stats.sum_abs_uy / slices + contact};
}

// In pair tests: what an entry costs (sorting it, copying it, starting its span), and what
// placing and copying a particle costs besides; fitted on the scenes of docs/performance.md's
// "bands" table (the default scene, N = 4000 of its kind, mixed, dense, faster than the box). The
// first sets how many bands pay, both what auto expects bands to cost.
inline constexpr double kBandsEntryCost = 40;
inline constexpr double kBandsParticleCost = 20;

// The band count for n swept boxes of mean width H_x L and height H_y L: B minimizes the pairs
// the bands test besides those whose boxes overlap, about n^2 H_x 1.4 / B, plus the entries past
// the first, n B H_y, at kBandsEntryCost pair tests each; at least 1 (then bands is sweep), at
// most n, and at most 16 / H_y: 17 entries a particle on average, so that a huge fast scene's
// entries stay countable in 32 bits (N <= 10^8).
inline std::uint32_t plan_bands(std::size_t n, double L, const PathSums& sums) {
  const double count = static_cast<double>(n);
  const double width = sums.width / count / L;
  const double height = std::max(sums.height / count / L, 1.0 / count);
  const double best = std::sqrt(1.4 * count * std::min(1.0, width) / (height * kBandsEntryCost));
  return static_cast<std::uint32_t>(
      std::clamp(std::round(std::min(best, 16 / height)), 1.0, count));
}

// The chance that two swept intervals of mean width H L overlap, for uniform positions.
inline double overlap_chance(double H) { return H >= 1 ? 1 : 2 * H - H * H; }

struct BandsPlan {
  std::uint32_t bands = 1, slices = 1;
  double cost = 0;  // estimated, in pair tests per sub-step
};

// The pairs of one slice's spans, from sweep's pairs (x intervals that overlap): those whose y
// intervals overlap too, and of the others the 1.4 / B that share a band; plus the placing, the
// copies and the entries.
inline double bands_slice_cost(std::size_t n, double L, const PathSums& sums,
                               std::uint32_t bands) {
  const double count = static_cast<double>(n), all_pairs = count * (count - 1) / 2;
  const double width = sums.width / std::max(1.0, count) / L;
  const double height = sums.height / std::max(1.0, count) / L;
  const double x_pairs = overlap_chance(width) * all_pairs, y_overlap = overlap_chance(height);
  return x_pairs * (y_overlap + (1 - y_overlap) * std::min(1.0, 1.4 / bands)) +
         kBandsParticleCost * count + kBandsEntryCost * count * (1 + bands * std::min(1.0, height));
}

// The slice count (1 to kMaxSlices, powers of 2) and band count of least estimated cost; at most
// 17 entries a piece (plan_bands), so K N <= 2^32 / 17 keeps the entries countable in 32 bits.
inline constexpr std::uint32_t kMaxSlices = 8;
inline BandsPlan plan_slices(std::size_t n, double L, double s, const SpeedStats& stats) {
  BandsPlan best;
  for (std::uint32_t slices = 1; slices <= kMaxSlices && (slices == 1 || 17.0 * slices * n <= 0x1p32);
       slices *= 2) {
    const PathSums sums = path_sums(n, s, stats, slices);
    const std::uint32_t bands = plan_bands(n, L, sums);
    const double cost = slices * bands_slice_cost(n, L, sums, bands);
    if (slices == 1 || cost < best.cost) best = {bands, slices, cost};
  }
  return best;
}

// The pieces' entries in slice and band order (keys: slice, band, x bucket, passers then
// starters), then the starters' copies (keys: slice, band, x bucket). Piece p of particle i is
// piece p n + i.
class BandsOrder {
 public:
  // Whether B is to be planned again: every kReplan sub-steps (as auto re-checks its choice: the
  // paths' lengths change as collisions spread the speeds) and whenever n changes.
  static constexpr std::uint32_t kReplan = 32;
  bool replan_due(std::size_t n) {
    const bool due = n != first_band_.size() || age_ == kReplan;
    age_ = due ? 1 : age_ + 1;
    return due;
  }
  // K slices of B bands of X = max(1, n / B) buckets each, for n particles.
  void plan(std::size_t n, double L, const BandsPlan& plan);
  // The bands and buckets of particles [lo, hi). A loop without branches or sums, which the
  // compiler vectorizes.
  void place(const World& w, std::size_t lo, std::size_t hi);
  // Serial: the entries and copies of every particle, sorted by key.
  void sort_entries(std::size_t n);
  // The copies of sorted positions [lo, hi), of all().
  void copy_sorted(const World& w, std::size_t lo, std::size_t hi);

  std::size_t entries() const { return entry_count_; }  // the rows: positions [0, entries())
  std::size_t all() const { return all_count_; }        // with the starters' copies

  std::uint32_t slices() const { return slices_; }
  // One past the last entry of slice p.
  std::uint32_t slice_end(std::uint32_t p) const {
    return end_[entry_key((p + 1) * bands_ * buckets_ - 1, true)];
  }

  // The pairs that entry k, of slice `part`, owns (header): one span. Both ends are computed and
  // one picked without a branch (starters and passers alternate unpredictably), and every span
  // takes the 8-lane loop: spans here are a few dozen long, so a branch on the length
  // mispredicts too.
  void test_partners(std::uint32_t k, double s2, ThreadScratch& out, TimeSlice part) const {
    const SpanArrays a{x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()};
    const RowParticle p{x_[k], y_[k], ux_[k], uy_[k], id_[k]};
    const std::uint32_t base = row_[k] >> 1, last = base + last_bucket_[k];
    const bool starter = row_[k] & 1;
    const std::uint32_t passer_begin = end_[copy_key(base + first_bucket_[k]) - 1];
    const std::uint32_t begin = starter ? k + 1 : passer_begin;
    const std::uint32_t end = starter ? end_[entry_key(last, true)] : end_[copy_key(last)];
    if (end <= begin) return;
    out.pair_tests += end - begin;
    test_copy_run(p, a, begin, end, s2, out, part);
  }

 private:
  // band_bucket = band * X + bucket.
  static std::uint32_t entry_key(std::uint32_t band_bucket, bool starter) {
    return 2 * band_bucket + starter;
  }
  std::uint32_t copy_key(std::uint32_t band_bucket) const { return copies_ + band_bucket; }

  // Monotone in v (a rounded product, then a clamp): the exactness argument needs only that,
  // whatever the rounding.
  static std::uint32_t bucket_of(double v, double per_length, double last) {
    return static_cast<std::uint32_t>(std::min(std::max(v * per_length, 0.0), last));
  }

  std::uint32_t age_ = 0;                  // sub-steps since the last plan
  std::uint32_t slices_ = 1, bands_ = 1, buckets_ = 1;  // K, B and X
  double per_x_ = 0, per_y_ = 0;                        // X / L and B / L
  std::uint32_t copies_ = 0;                            // the first copy key: 2 K B X
  std::size_t entry_count_ = 0, all_count_ = 0;
  // Per piece.
  std::vector<std::uint32_t> first_band_, last_band_, start_bucket_, end_bucket_;
  // Per key: one past its last sorted position.
  std::vector<std::uint32_t> end_;
  // Per sorted position.
  std::vector<double> x_, y_, ux_, uy_;
  std::vector<std::uint32_t> id_;
  // Per row: (slice B + band) X << 1 | starter, and the x buckets of its interval's start and
  // end.
  std::vector<std::uint32_t> row_, first_bucket_, last_bucket_;
};

class BandsBroadPhase {
 public:
  // Sorted entries per piece, as sweep's positions.
  static constexpr std::uint32_t kChunk = 32;

  // bands = 0: bands and slices planned from the paths (plan_slices); else both fixed (for the
  // tests).
  explicit BandsBroadPhase(std::uint32_t bands = 0, std::uint32_t slices = 1)
      : fixed_{bands, slices} {}
  // The relay (parallel/relay.hpp) gives each of its closers a copy of the engine's broad phase.
  BandsBroadPhase(const BandsBroadPhase& other)
      : fixed_(other.fixed_),
        orders_(other.orders_),
        one_order_(other.one_order_.load(std::memory_order_relaxed)) {}
  BandsBroadPhase& operator=(const BandsBroadPhase&) = delete;

  // As sweep's: with a private state every thread builds its own order (no barrier); else the
  // placing and the copies are split over the team and the counting sort is one thread's.
  void prepare(const World& w) {
    const std::size_t n = w.n;
    if (uses_private_state(n)) {
      fit_to_team(orders_);
      one_order_.store(omp_get_num_threads() == 1, std::memory_order_relaxed);
      BandsOrder& mine = orders_[static_cast<std::size_t>(omp_get_thread_num())];
      if (mine.replan_due(n)) mine.plan(n, w.L, plan_for(w));
      mine.place(w, 0, n);
      mine.sort_entries(n);
      mine.copy_sorted(w, 0, mine.all());
      return;
    }
    BandsOrder& shared = orders_[0];
#pragma omp single
    if (shared.replan_due(n)) shared.plan(n, w.L, plan_for(w));
    const int t = omp_get_thread_num(), threads = omp_get_num_threads();
    shared.place(w, n * t / threads, n * (t + 1) / threads);
#pragma omp barrier
#pragma omp single
    shared.sort_entries(n);
    const std::size_t all = shared.all();
    shared.copy_sorted(w, all * t / threads, all * (t + 1) / threads);
#pragma omp barrier
  }

  std::uint32_t chunks(const World& w) const {
    const std::size_t entries = order_for(w).entries();
    return static_cast<std::uint32_t>((entries + kChunk - 1) / kChunk);
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const BandsOrder& order = order_for(w);
    const auto entries = static_cast<std::uint32_t>(order.entries());
    const std::uint32_t first = c * kChunk, last = std::min(entries, first + kChunk);
    TimeSlice part{0, order.slices()};
    std::uint32_t part_end = order.slice_end(0);
    for (std::uint32_t k = first; k < last; ++k) {
      while (k >= part_end) part_end = order.slice_end(++part.slice);
      order.test_partners(k, w.s2, out, part);
    }
  }

  std::string name() const { return "bands"; }

 private:
  // One O(N) pass per plan, on one thread.
  BandsPlan plan_for(const World& w) const {
    if (fixed_.bands) return fixed_;
    SpeedStats stats;
    for (std::size_t i = 0; i < w.n; ++i) stats.add(w.ux[i], w.uy[i]);
    return plan_slices(w.n, w.L, w.s, stats);
  }

  const BandsOrder& order_for(const World& w) const {
    const bool own = uses_private_state(w.n) && !one_order_.load(std::memory_order_relaxed);
    return orders_[own ? static_cast<std::size_t>(omp_get_thread_num()) : 0];
  }

  BandsPlan fixed_;
  std::vector<BandsOrder> orders_ = std::vector<BandsOrder>(1);
  std::atomic<bool> one_order_{true};  // the last prepare() ran on a team of one
};

inline void BandsOrder::plan(std::size_t n, double L, const BandsPlan& plan) {
  slices_ = plan.slices;
  bands_ = plan.bands;
  buckets_ = static_cast<std::uint32_t>(std::max<std::size_t>(1, n / bands_));
  per_x_ = buckets_ / L;
  per_y_ = bands_ / L;
  copies_ = 2 * slices_ * bands_ * buckets_;
  const std::size_t pieces = n * slices_;
  first_band_.resize(pieces);
  last_band_.resize(pieces);
  start_bucket_.resize(pieces);
  end_bucket_.resize(pieces);
}

inline void BandsOrder::place(const World& w, std::size_t lo, std::size_t hi) {
  const double last_band = bands_ - 1, last_bucket = buckets_ - 1, part = 1.0 / slices_;
  const std::size_t n = w.n;
  for (std::uint32_t p = 0; p < slices_; ++p) {
    const double from = p * part;  // exact: slices_ is a power of 2
    for (std::size_t i = lo; i < hi; ++i) {
      const double ux = w.ux[i] * part, uy = w.uy[i] * part;
      const double x = w.x[i] + w.ux[i] * from, y = w.y[i] + w.uy[i] * from;
      const double x_start = x - padded(std::max(0.0, -ux) + w.r, w.L);
      const double x_end = x + padded(std::max(0.0, ux) + w.r, w.L);
      const double y_start = y - padded(std::max(0.0, -uy) + w.r, w.L);
      const double y_end = y + padded(std::max(0.0, uy) + w.r, w.L);
      const std::size_t q = p * n + i;
      first_band_[q] = bucket_of(y_start, per_y_, last_band);
      last_band_[q] = bucket_of(y_end, per_y_, last_band);
      start_bucket_[q] = bucket_of(x_start, per_x_, last_bucket);
      end_bucket_[q] = bucket_of(x_end, per_x_, last_bucket);
    }
  }
}

inline void BandsOrder::sort_entries(std::size_t n) {
  const std::uint32_t X = buckets_, BX = bands_ * X;
  end_.assign(static_cast<std::size_t>(3) * slices_ * BX, 0u);
  entry_count_ = 0;
  for (std::uint32_t p = 0; p < slices_; ++p)
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t q = p * n + i;
      const std::uint32_t first = first_band_[q], start = p * BX + start_bucket_[q];
      ++end_[entry_key(first * X + start, true)];
      ++end_[copy_key(first * X + start)];
      for (std::uint32_t b = first + 1; b <= last_band_[q]; ++b)
        ++end_[entry_key(b * X + start, false)];
      entry_count_ += last_band_[q] - first + 1;
    }
  std::uint32_t run = 0;
  for (std::uint32_t& e : end_) {
    const std::uint32_t count = e;
    e = run;  // the scatter cursor; it ends at the key's end
    run += count;
  }
  all_count_ = run;
  id_.resize(all_count_ + kSpanPadding);
  row_.resize(entry_count_);
  first_bucket_.resize(entry_count_);
  last_bucket_.resize(entry_count_);
  for (std::uint32_t p = 0; p < slices_; ++p)
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t q = p * n + i;
      const auto id = static_cast<std::uint32_t>(i);
      const std::uint32_t first = first_band_[q], start = p * BX + start_bucket_[q];
      const std::uint32_t from = start_bucket_[q], to = end_bucket_[q];
      const std::uint32_t k = end_[entry_key(first * X + start, true)]++;
      id_[k] = id;
      row_[k] = (p * BX + first * X) << 1 | 1u;
      first_bucket_[k] = from;
      last_bucket_[k] = to;
      id_[end_[copy_key(first * X + start)]++] = id;
      for (std::uint32_t b = first + 1; b <= last_band_[q]; ++b) {
        const std::uint32_t e = end_[entry_key(b * X + start, false)]++;
        id_[e] = id;
        row_[e] = (p * BX + b * X) << 1;
        first_bucket_[e] = from;
        last_bucket_[e] = to;
      }
    }
  x_.resize(all_count_ + kSpanPadding);
  y_.resize(all_count_ + kSpanPadding);
  ux_.resize(all_count_ + kSpanPadding);
  uy_.resize(all_count_ + kSpanPadding);
}

inline void BandsOrder::copy_sorted(const World& w, std::size_t lo, std::size_t hi) {
  for (std::size_t k = lo; k < hi; ++k) {
    const std::uint32_t i = id_[k];
    x_[k] = w.x[i];
    y_[k] = w.y[i];
    ux_[k] = w.ux[i];
    uy_[k] = w.uy[i];
  }
}

}  // namespace particle::detail
