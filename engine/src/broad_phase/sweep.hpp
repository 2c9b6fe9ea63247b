#pragma once
// Sweep broad phase: sort-and-sweep over swept bounding boxes, for fast scenes (the default scene
// moves up to a quarter of the box per step, where cells cannot prune).
//
// Each particle's swept interval on x is the x-extent of its disk over the sub-step,
// [min(x, x + ux) - r, max(x, x + ux) + r], padded (see broad_phase/common.hpp): two disks can only
// touch at some t in [0, 1] if these intervals overlap. It is half as wide as the symmetric
// [x - |ux| - r, x + |ux| + r], which halves the pairs tested in fast scenes. Particles are sorted
// into N buckets of interval start (a counting sort, O(N)); the partners of the particle at
// position k that come after it are positions k+1 .. the end of the bucket of its interval's end,
// one contiguous span of a copy of the particles in that order, which the narrow phase tests in
// one vectorized loop. Each pair of overlapping intervals is tested once, from the earlier of the
// two: one in a later bucket starts after k's start, and is in the span if it starts before k's
// end (bucket_of is monotone); one in k's own bucket is in the span of whichever comes first.
//
// The order within a bucket does not matter, so there is no finishing sort: every span runs to a
// bucket's end whatever the order in it, so sorting within buckets changed no test (it cost a
// tenth of auto's loop on the default scene in mispredicted branches). The buckets also find each
// span's end in O(1) instead of a binary search (which cost 15% of the run). Cost per sub-step:
// O(N) plus the overlapping pairs, about 2H/L - (H/L)^2 of all pairs for uniform positions and H
// the mean interval width (about 0.12 L in the default scene, so about a fifth of all pairs).
#include <algorithm>
#include <atomic>
#include <cmath>
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

// What a sort needs of every particle: the smallest interval start and the largest velocity
// component (for the float pre-test's bounds).
struct StartStats {
  double smallest = 0, fastest = 0;

  void merge(const StartStats& o) {
    smallest = std::min(smallest, o.smallest);
    fastest = std::max(fastest, o.fastest);
  }
};

// The particles in bucket order of swept-interval start, with what find_pairs needs to walk them.
class SweepOrder {
 public:
  void resize(const World& w) {
    const std::size_t n = w.n;
    start_.resize(n);
    bucket_.resize(n);
    stop_bucket_.resize(n);
    bucket_end_.resize(n);
    id_.resize(n + kSpanPadding);
  }

  StartStats compute_starts(const World& w, std::size_t lo, std::size_t hi) {
    std::int64_t smallest = ordered_bits(0), fastest = ordered_bits(0);
    for (std::size_t i = lo; i < hi; ++i) {
      start_[i] = swept_start(w.x[i], w.ux[i], w.r, w.L);
      smallest = std::min(smallest, ordered_bits(start_[i]));
      fastest = std::max(fastest, ordered_bits(axis_speed(w, i)));
    }
    return {from_ordered_bits(smallest), from_ordered_bits(fastest)};
  }

  // The float copies where the float pre-test applies, else the double ones (test_rows).
  void copy_sorted(const World& w, std::size_t lo, std::size_t hi) {
    if (pretest_)
      copy_floats_in_order(w, id_.data(), lo, hi, xf_.data(), yf_.data(), uxf_.data(), uyf_.data());
    else
      copy_in_order(w, id_.data(), lo, hi, x_.data(), y_.data(), ux_.data(), uy_.data());
  }

  // id_ in bucket order of interval start, bucket_end_ the end of every bucket; the float
  // pre-test's bounds where it applies.
  void sort_by_start(const World& w, const StartStats& stats);

  // Tests each particle at positions [k_begin, k_end) against every later one whose interval
  // overlaps, and the few others up to the end of the bucket of its interval's end. Out of line,
  // called once a chunk: inlined into auto's team function, whose register allocation sees every
  // engine at once, its loop's row values were spilled and reloaded at every step whenever that
  // function changed elsewhere (the default scene's auto once counted 7% more instructions).
  [[gnu::noinline]] void test_partners(const World& w, std::uint32_t k_begin, std::uint32_t k_end,
                                       ThreadScratch& out) const {
    // A row's span ends one past the last sorted position whose start is <= the end of its
    // interval, or a little further: at the end of the bucket of that end, which holds about one
    // start. Testing the few pairs past it costs less than finding the exact end (a loop whose
    // exit the branch predictor misses). The arrays by value: read through `this`, every store of
    // the float groups' stream (which may alias anything) made the loop load them again.
    const std::uint32_t* bucket_end = bucket_end_.data();
    const std::uint32_t* id = id_.data();
    const std::uint32_t* stop_bucket = stop_bucket_.data();
    test_rows(w, {x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()},
              {xf_.data(), yf_.data(), uxf_.data(), uyf_.data()}, pretest_ ? &*pretest_ : nullptr,
              k_begin, k_end, out, [=](std::uint32_t k) {
                return std::pair{k + 1, std::max(k + 1, bucket_end[stop_bucket[id[k]]])};
              });
  }

 private:
  // The bucket of an interval start or end: monotone in v, so every bucket is one contiguous
  // range of the sorted starts. N buckets over [smallest start, L]; ends past L share the last.
  struct Buckets {
    double origin = 0, per_length = 0, last = 0;
    std::uint32_t of(double v) const {
      return static_cast<std::uint32_t>(std::min(std::max((v - origin) * per_length, 0.0), last));
    }
#ifdef __AVX2__
    // of() of four values, the same operations in the same order.
    __m128i of(__m256d v) const {
      return _mm256_cvttpd_epi32(_mm256_min_pd(
          _mm256_max_pd(
              _mm256_mul_pd(_mm256_sub_pd(v, _mm256_set1_pd(origin)), _mm256_set1_pd(per_length)),
              _mm256_setzero_pd()),
          _mm256_set1_pd(last)));
    }
#endif
  };

  Buckets buckets_;
  std::vector<double> start_;                        // interval starts, by id
  std::vector<std::uint32_t> bucket_, stop_bucket_;  // of each interval's start and end, by id
  std::vector<std::uint32_t> bucket_end_;            // one past each bucket's last sorted position
  std::vector<double> x_, y_, ux_, uy_;  // by sorted position, where the pre-test does not apply
  std::vector<std::uint32_t> id_;
  LineAligned<float> xf_, yf_, uxf_, uyf_;  // x_ .. uy_ in float, where the pre-test applies
  std::optional<FloatPretest> pretest_;
};

class SweepBroadPhase {
 public:
  // Sorted positions per piece: about 30 pieces on the default scene (16, 64 and 128 measured
  // the same within noise with the relay at T = 3 and 8 on 2 cores).
  static constexpr std::uint32_t kChunk = 32;

  SweepBroadPhase() = default;
  // The relay (parallel/relay.hpp) gives each of its closers a copy of the engine's broad phase.
  SweepBroadPhase(const SweepBroadPhase& other)
      : orders_(other.orders_),
        one_order_(other.one_order_.load(std::memory_order_relaxed)),
        start_stats_(other.start_stats_),
        builds_(other.builds_) {}
  SweepBroadPhase& operator=(const SweepBroadPhase&) = delete;

  // With a private state (parallel/private_state.hpp) every thread builds its own SweepOrder from
  // its own copy: a few microseconds of duplicated work, instead of one thread working while the
  // others wait at a barrier and then fetch its result from another core's cache. The relay
  // (parallel/relay.hpp) calls this on a team of one, and every thread then reads that one order.
  void prepare(const World& w) {
    const std::size_t n = w.n;
    const int t = omp_get_thread_num();
    if (t == 0) ++builds_;
    if (uses_private_state(n)) {
      fit_to_team(orders_);
      // Written alike by every thread of a team, so never a conflicting value.
      one_order_.store(omp_get_num_threads() == 1, std::memory_order_relaxed);
      SweepOrder& mine = orders_[static_cast<std::size_t>(t)];
      mine.resize(w);
      mine.sort_by_start(w, mine.compute_starts(w, 0, n));
      mine.copy_sorted(w, 0, n);
      return;
    }
    SweepOrder& shared = orders_[0];
    team_single([&] {
      shared.resize(w);
      start_stats_.assign(omp_get_num_threads(), StartStats{});
    });
    const int threads = omp_get_num_threads();
    const std::size_t lo = n * t / threads, hi = n * (t + 1) / threads;
    start_stats_[t] = shared.compute_starts(w, lo, hi);
    team_barrier();
    team_single([&] {
      StartStats all;
      for (const StartStats& s : start_stats_) all.merge(s);
      shared.sort_by_start(w, all);
    });
    shared.copy_sorted(w, lo, hi);
    team_barrier();
  }

  std::uint32_t chunks(const World& w) const {
    return static_cast<std::uint32_t>((w.n + kChunk - 1) / kChunk);
  }

  void find_pairs_in(const World& w, std::uint32_t c, ThreadScratch& out) const {
    const bool own = uses_private_state(w.n) && !one_order_.load(std::memory_order_relaxed);
    const SweepOrder& order = orders_[own ? static_cast<std::size_t>(omp_get_thread_num()) : 0];
    const auto n = static_cast<std::uint32_t>(w.n);
    order.test_partners(w, c * kChunk, std::min(n, (c + 1) * kChunk), out);
  }

  std::string name() const { return "sweep"; }
  std::uint64_t builds() const { return builds_; }  // one a sub-step

 private:
  std::vector<SweepOrder> orders_ = std::vector<SweepOrder>(1);
  std::atomic<bool> one_order_{true};    // the last prepare() ran on a team of one
  std::vector<StartStats> start_stats_;  // per thread
  std::uint64_t builds_ = 0;
};

inline void SweepOrder::sort_by_start(const World& w, const StartStats& stats) {
  const std::size_t n = w.n;
  // Positions stay in [0, L] (docs/model.md), so L bounds every coordinate.
  pretest_.reset();
  // The copies the pair search reads: float where the float pre-test applies, else double.
  if (FloatPretest::applies(w.s, w.L, stats.fastest)) {
    pretest_.emplace(w.s, w.L, stats.fastest);
    for (auto* v : {&xf_, &yf_, &uxf_, &uyf_}) v->resize(n + kFloatSpanPadding);
  } else {
    for (auto* v : {&x_, &y_, &ux_, &uy_}) v->resize(n + kSpanPadding);
  }
  buckets_ = {stats.smallest, static_cast<double>(n) / (w.L - stats.smallest),
              static_cast<double>(n - 1)};
  std::size_t i = 0;
#ifdef __AVX2__
  // Four particles a register, Buckets::of() and swept_end() on lanes (scalar, the loop was a
  // third of the sort on the default scene).
  const __m256d r = _mm256_set1_pd(w.r), zero = _mm256_setzero_pd();
  for (; i + 4 <= n; i += 4) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(bucket_.data() + i),
                     buckets_.of(_mm256_loadu_pd(start_.data() + i)));
    const __m256d reach = _mm256_add_pd(_mm256_max_pd(_mm256_loadu_pd(w.ux + i), zero), r);
    _mm_storeu_si128(reinterpret_cast<__m128i*>(stop_bucket_.data() + i),
                     buckets_.of(_mm256_add_pd(_mm256_loadu_pd(w.x + i), padded(reach, w.L))));
  }
#endif
  for (; i < n; ++i) {
    bucket_[i] = buckets_.of(start_[i]);
    stop_bucket_[i] = buckets_.of(swept_end(w.x[i], w.ux[i], w.r, w.L));
  }
  std::fill(bucket_end_.begin(), bucket_end_.end(), 0u);
  for (i = 0; i < n; ++i) ++bucket_end_[bucket_[i]];
  std::uint32_t run = 0;
  for (std::size_t b = 0; b < n; ++b) {
    const std::uint32_t count = bucket_end_[b];
    bucket_end_[b] = run;  // the scatter cursor; it ends at the bucket's end
    run += count;
  }
  for (i = 0; i < n; ++i) id_[bucket_end_[bucket_[i]]++] = static_cast<std::uint32_t>(i);
}

}  // namespace particle::detail
