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
// Cost per sub-step: O(N B H) entries by a counting sort, plus the pairs of the spans, one span
// per entry as sweep has one per particle (an entry costs about 40 pair tests on the default
// scene: a second span per starter cost more than the bands saved). The candidate set is
// brute's, so the order of the tests does not matter.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "broad_phase/common.hpp"
#include "parallel/private_state.hpp"
#include "parallel/team.hpp"
#include "step/float_pretest.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail {

// The swept intervals' lengths, summed over the particles: what plans the bands.
struct PathSums {
  double width = 0, height = 0;
};

// From the displacement statistics of n particles of contact distance s (auto's, or bands' own).
inline PathSums path_sums(std::size_t n, double s, const SpeedStats& stats) {
  const double contact = static_cast<double>(n) * s;
  return {stats.sum_abs_ux + contact, stats.sum_abs_uy + contact};
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

// The particles' entries in band order (keys: band, x bucket, passers then starters), then the
// starters' copies (keys: band, x bucket).
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
  // B bands of X = max(1, n / B) buckets each, for n particles.
  void plan(std::size_t n, double L, std::uint32_t bands);
  // The bands and buckets of particles [lo, hi). A loop without branches, which the compiler
  // vectorizes. Returns their largest velocity component (for the float pre-test's bounds).
  double place(const World& w, std::size_t lo, std::size_t hi);
  // Serial: the entries and copies of every particle, sorted by key; the float pre-test's bounds
  // where it applies, from the largest velocity component of all.
  void sort_entries(const World& w, double fastest);
  // The copies of sorted positions [lo, hi), of all().
  void copy_sorted(const World& w, std::size_t lo, std::size_t hi);

  std::size_t entries() const { return entry_count_; }  // the rows: positions [0, entries())
  std::size_t all() const { return all_count_; }        // with the starters' copies

  // Entries [k_begin, k_end), each against the pairs it owns (header): one span.
  void test_partners(const World& w, std::uint32_t k_begin, std::uint32_t k_end,
                     ThreadScratch& out) const {
    // Read by value, as sweep's. Both ends are computed and one picked without a branch
    // (starters and passers alternate unpredictably).
    const std::uint32_t *row = row_.data(), *id = id_.data(), *end = end_.data();
    const std::uint32_t *start_bucket = start_bucket_.data(), *end_bucket = end_bucket_.data();
    const Keys keys = key_space_;
    test_rows(w, {x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()},
              {xf_.data(), yf_.data(), uxf_.data(), uyf_.data()}, pretest_ ? &*pretest_ : nullptr,
              k_begin, k_end, out, [=](std::uint32_t k) {
                const std::uint32_t key = row[k], band_bucket = key >> 1, i = id[k];
                const std::uint32_t last = band_bucket - start_bucket[i] + end_bucket[i];
                const std::uint32_t passer_begin = end[keys.copy(band_bucket) - 1];
                // All ones for a starter: a select GCC made a branch, mispredicted at every
                // change of kind.
                const std::uint32_t starter = 0u - (key & 1);
                const std::uint32_t begin = ((k + 1) & starter) | (passer_begin & ~starter);
                const std::uint32_t stop =
                    (end[Keys::entry(last, true)] & starter) | (end[keys.copy(last)] & ~starter);
                return std::pair{begin, std::max(begin, stop)};
              });
  }

 private:
  // The sort's keys, band_bucket = band * X + bucket: each bucket's passers, then its starters,
  // then after every entry's key the starters' copies.
  struct Keys {
    std::uint32_t copies = 0;  // the first copy key: 2 B X
    static std::uint32_t entry(std::uint32_t band_bucket, bool starter) {
      return 2 * band_bucket + starter;
    }
    std::uint32_t copy(std::uint32_t band_bucket) const { return copies + band_bucket; }
  };

  // Monotone in v (a rounded product, then a clamp): the exactness argument needs only that,
  // whatever the rounding.
  static std::uint32_t bucket_of(double v, double per_length, double last) {
    return static_cast<std::uint32_t>(std::min(std::max(v * per_length, 0.0), last));
  }

  // A particle's starter and up to kUnrolled - 1 passers are written without a branch.
  static constexpr std::uint32_t kUnrolled = 4;

  std::uint32_t age_ = 0;                  // sub-steps since the last plan
  std::uint32_t bands_ = 1, buckets_ = 1;  // B and X
  double per_x_ = 0, per_y_ = 0;           // X / L and B / L
  Keys key_space_;
  std::size_t entry_count_ = 0, all_count_ = 0;
  // Per particle.
  std::vector<std::uint32_t> first_band_, last_band_, start_bucket_, end_bucket_;
  // Per key: one past its last sorted position.
  std::vector<std::uint32_t> end_;
  // Per entry in particle order, before the sort: its key and particle.
  std::vector<std::uint32_t> keys_, owners_;
  // Per sorted position (x_ .. uy_ where the float pre-test does not apply).
  std::vector<double> x_, y_, ux_, uy_;
  std::vector<std::uint32_t> id_;
  LineAligned<float> xf_, yf_, uxf_, uyf_;  // x_ .. uy_ in float, where the pre-test applies
  std::optional<FloatPretest> pretest_;
  // Per row: its key.
  std::vector<std::uint32_t> row_;
};

class BandsBroadPhase {
 public:
  // Sorted entries per piece, as sweep's positions.
  static constexpr std::uint32_t kChunk = 32;

  // bands = 0: planned from the paths (plan_bands); else fixed (for the tests).
  explicit BandsBroadPhase(std::uint32_t bands = 0) : fixed_bands_(bands) {}
  // The relay (parallel/relay.hpp) gives each of its closers a copy of the engine's broad phase.
  BandsBroadPhase(const BandsBroadPhase& other)
      : fixed_bands_(other.fixed_bands_),
        orders_(other.orders_),
        one_order_(other.one_order_.load(std::memory_order_relaxed)),
        builds_(other.builds_) {}
  BandsBroadPhase& operator=(const BandsBroadPhase&) = delete;

  // As sweep's: with a private state every thread builds its own order (no barrier); else the
  // placing and the copies are split over the team and the counting sort is one thread's.
  void prepare(const World& w) {
    const std::size_t n = w.n;
    const int t = omp_get_thread_num();
    if (t == 0) ++builds_;
    if (uses_private_state(n)) {
      fit_to_team(orders_);
      one_order_.store(omp_get_num_threads() == 1, std::memory_order_relaxed);
      BandsOrder& mine = orders_[static_cast<std::size_t>(t)];
      if (mine.replan_due(n)) mine.plan(n, w.L, bands_for(w));
      mine.sort_entries(w, mine.place(w, 0, n));
      mine.copy_sorted(w, 0, mine.all());
      return;
    }
    BandsOrder& shared = orders_[0];
    team_single([&] {
      if (shared.replan_due(n)) shared.plan(n, w.L, bands_for(w));
      fastest_.assign(static_cast<std::size_t>(omp_get_num_threads()), 0.0);
    });
    const int threads = omp_get_num_threads();
    fastest_[static_cast<std::size_t>(t)] = shared.place(w, n * t / threads, n * (t + 1) / threads);
    team_barrier();
    team_single(
        [&] { shared.sort_entries(w, *std::max_element(fastest_.begin(), fastest_.end())); });
    const std::size_t all = shared.all();
    shared.copy_sorted(w, all * t / threads, all * (t + 1) / threads);
    team_barrier();
  }

  std::uint32_t chunks(const World& w) const {
    const std::size_t entries = order_for(w).entries();
    return static_cast<std::uint32_t>((entries + kChunk - 1) / kChunk);
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const BandsOrder& order = order_for(w);
    const auto entries = static_cast<std::uint32_t>(order.entries());
    order.test_partners(w, c * kChunk, std::min(entries, (c + 1) * kChunk), out);
  }

  std::string name() const { return "bands"; }
  std::uint64_t builds() const { return builds_; }  // one a sub-step

 private:
  // One O(N) pass per plan, on one thread.
  std::uint32_t bands_for(const World& w) const {
    if (fixed_bands_) return fixed_bands_;
    SpeedStats stats;
    for (std::size_t i = 0; i < w.n; ++i) stats.add(w.ux[i], w.uy[i]);
    return plan_bands(w.n, w.L, path_sums(w.n, w.s, stats));
  }

  const BandsOrder& order_for(const World& w) const {
    const bool own = uses_private_state(w.n) && !one_order_.load(std::memory_order_relaxed);
    return orders_[own ? static_cast<std::size_t>(omp_get_thread_num()) : 0];
  }

  std::uint32_t fixed_bands_;
  std::vector<BandsOrder> orders_ = std::vector<BandsOrder>(1);
  std::atomic<bool> one_order_{true};  // the last prepare() ran on a team of one
  std::vector<double> fastest_;        // per thread: place()'s
  std::uint64_t builds_ = 0;
};

inline void BandsOrder::plan(std::size_t n, double L, std::uint32_t bands) {
  bands_ = bands;
  buckets_ = static_cast<std::uint32_t>(std::max<std::size_t>(1, n / bands));
  per_x_ = buckets_ / L;
  per_y_ = bands / L;
  key_space_.copies = 2 * bands * buckets_;
  first_band_.resize(n);
  last_band_.resize(n);
  start_bucket_.resize(n);
  end_bucket_.resize(n);
}

inline double BandsOrder::place(const World& w, std::size_t lo, std::size_t hi) {
  const double last_band = bands_ - 1, last_bucket = buckets_ - 1;
  std::int64_t fastest = ordered_bits(0);
  for (std::size_t i = lo; i < hi; ++i) {
    const double x_start = swept_start(w.x[i], w.ux[i], w.r, w.L);
    const double x_end = swept_end(w.x[i], w.ux[i], w.r, w.L);
    const double y_start = swept_start(w.y[i], w.uy[i], w.r, w.L);
    const double y_end = swept_end(w.y[i], w.uy[i], w.r, w.L);
    first_band_[i] = bucket_of(y_start, per_y_, last_band);
    last_band_[i] = bucket_of(y_end, per_y_, last_band);
    start_bucket_[i] = bucket_of(x_start, per_x_, last_bucket);
    end_bucket_[i] = bucket_of(x_end, per_x_, last_bucket);
    fastest = std::max(fastest, ordered_bits(axis_speed(w, i)));
  }
  return from_ordered_bits(fastest);
}

// The entries are first written out in particle order, then counted and scattered: a loop over
// each particle's bands, once to count and once to place, missed its exit about once a particle
// each time (a fifth of the default scene's run).
inline void BandsOrder::sort_entries(const World& w, double fastest) {
  const std::size_t n = w.n;
  const std::uint32_t X = buckets_;
  // Positions stay in [0, L] (docs/model.md), so L bounds every coordinate.
  pretest_.reset();
  if (FloatPretest::applies(w.s, w.L, fastest)) pretest_.emplace(w.s, w.L, fastest);
  entry_count_ = 0;
  for (std::size_t i = 0; i < n; ++i) entry_count_ += last_band_[i] - first_band_[i] + 1;
  keys_.resize(entry_count_ + kUnrolled);
  owners_.resize(entry_count_ + kUnrolled);
  std::size_t m = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto id = static_cast<std::uint32_t>(i);
    const std::uint32_t band_bucket = first_band_[i] * X + start_bucket_[i];
    const std::uint32_t count = last_band_[i] - first_band_[i] + 1;
    // Past count the keys are junk, overwritten by the next particle's or past the last entry.
    for (std::uint32_t d = 0; d < kUnrolled; ++d) {
      keys_[m + d] = Keys::entry(band_bucket + d * X, d == 0);
      owners_[m + d] = id;
    }
    for (std::uint32_t d = kUnrolled; d < count; ++d) {
      keys_[m + d] = Keys::entry(band_bucket + d * X, false);
      owners_[m + d] = id;
    }
    m += count;
  }
  end_.assign(static_cast<std::size_t>(3) * bands_ * X, 0u);
  for (std::size_t e = 0; e < entry_count_; ++e) ++end_[keys_[e]];
  // A starters' copy for every starter.
  for (std::uint32_t band_bucket = 0; band_bucket < key_space_.copies / 2; ++band_bucket)
    end_[key_space_.copy(band_bucket)] = end_[Keys::entry(band_bucket, true)];
  std::uint32_t run = 0;
  for (std::uint32_t& e : end_) {
    const std::uint32_t count = e;
    e = run;  // the scatter cursor; it ends at the key's end
    run += count;
  }
  all_count_ = run;
  id_.resize(all_count_ + kSpanPadding);
  row_.resize(entry_count_);
  for (std::size_t e = 0; e < entry_count_; ++e) {
    const std::uint32_t k = end_[keys_[e]]++;
    id_[k] = owners_[e];
    row_[k] = keys_[e];
  }
  for (std::size_t i = 0; i < n; ++i)
    id_[end_[key_space_.copy(first_band_[i] * X + start_bucket_[i])]++] =
        static_cast<std::uint32_t>(i);
  if (pretest_)
    for (auto* v : {&xf_, &yf_, &uxf_, &uyf_}) v->resize(all_count_ + kFloatSpanPadding);
  else
    for (auto* v : {&x_, &y_, &ux_, &uy_}) v->resize(all_count_ + kSpanPadding);
}

// The float copies where the float pre-test applies, else the double ones (test_rows).
inline void BandsOrder::copy_sorted(const World& w, std::size_t lo, std::size_t hi) {
  if (pretest_)
    copy_floats_in_order(w, id_.data(), lo, hi, xf_.data(), yf_.data(), uxf_.data(), uyf_.data());
  else
    copy_in_order(w, id_.data(), lo, hi, x_.data(), y_.data(), ux_.data(), uy_.data());
}

}  // namespace particle::detail
