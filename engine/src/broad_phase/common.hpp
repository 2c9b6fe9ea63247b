#pragma once
// Helpers shared by the pruning broad phases (grid, cells, sweep): the conservative reach and
// per-thread slots for team reductions.
//
// Reach. Two particles can only touch within a sub-step if, at its start and on each axis,
// |dx| <= s + |ux_i| + |ux_j|: a candidate needs a time t in [0, 1] with |d + w t| <= s, and
// |w_x| <= |ux_i| + |ux_j|. The narrow phase decides in floating point, so a pair a hair outside
// that bound could still pass it by rounding; every broad phase therefore pads its reach with
// padded(): a relative 2^-20 (about 1e-6, a million times the relative rounding of the pair
// terms) plus an absolute L * 2^-40 (thousands of ulps of any coordinate in [0, L], which covers
// the rounding of x +- reach and of the cell index x / cell). The padding costs nothing
// measurable in pruning and makes every engine exact: it may test more pairs, never fewer.
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__AVX512F__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "parallel/team.hpp"
#include "step/stages.hpp"
#include "world.hpp"

namespace particle::detail {

// padded()'s factor and its share of L, named for the vector loops that pad four reaches at once.
inline constexpr double kPadFactor = 1 + 0x1p-20, kPadOfL = 0x1p-40;
inline double padded(double reach, double L) { return reach * kPadFactor + L * kPadOfL; }
#ifdef __AVX2__
// padded() of four reaches.
inline __m256d padded(__m256d reach, double L) {
  return _mm256_add_pd(_mm256_mul_pd(reach, _mm256_set1_pd(kPadFactor)),
                       _mm256_set1_pd(L * kPadOfL));
}
// |v| of four lanes (AVX2 has no abs).
inline __m256d abs_lanes(__m256d v) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), v); }
#endif

// A finite double's bits as an integer of the same order, and back: a loop's minimum or maximum
// of doubles taken on these stays vectorized (GCC keeps a double one scalar, for its NaN rules;
// sweep's starts took 14 cycles a particle so).
inline std::int64_t ordered_bits(double v) {
  const auto b = std::bit_cast<std::int64_t>(v);
  return b ^ ((b >> 63) & INT64_MAX);
}
inline double from_ordered_bits(std::int64_t b) {
  return std::bit_cast<double>(b ^ ((b >> 63) & INT64_MAX));
}

// A disk's swept interval on one axis over the sub-step, [min(x, x + u) - r, max(x, x + u) + r],
// padded: two disks can touch at some t in [0, 1] only if theirs overlap on both axes.
inline double swept_start(double x, double u, double r, double L) {
  return x - padded(std::max(0.0, -u) + r, L);
}
inline double swept_end(double x, double u, double r, double L) {
  return x + padded(std::max(0.0, u) + r, L);
}

// The largest per-axis displacement of particle i in this sub-step.
PARTICLE_HD inline double axis_speed(const World& w, std::size_t i) {
  return std::max(std::fabs(w.ux[i]), std::fabs(w.uy[i]));
}

// The cell column (or row), of n, of coordinate x, with inverse_cell = n / L; rounding is covered
// by padded(). Clamped in double first: x +- reach may be far out.
PARTICLE_HD inline std::uint32_t cell_column(double x, double inverse_cell, std::uint32_t n) {
  const double c = x * inverse_cell;
  return c <= 0 ? 0u : (c >= n - 1 ? n - 1 : static_cast<std::uint32_t>(c));
}

// A sorting broad phase's copy of the particles in its order: positions [lo, hi) of x, y, ux, uy
// get the values of particles id[lo, hi). With AVX-512, eight positions at a time, four gathers
// and four full-width stores: the scalar loop was bound by its stores (four per position).
inline void copy_in_order(const World& w, const std::uint32_t* id, std::size_t lo, std::size_t hi,
                          double* x, double* y, double* ux, double* uy) {
  std::size_t k = lo;
#ifdef __AVX512F__
  for (; k + 8 <= hi; k += 8) {
    // The masked form with a zero source: GCC 12's plain gather leaves its source undefined and
    // warns (-Wmaybe-uninitialized).
    const __m256i i = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(id + k));
    const __m512d zero = _mm512_setzero_pd();
    _mm512_storeu_pd(x + k, _mm512_mask_i32gather_pd(zero, 0xFF, i, w.x, 8));
    _mm512_storeu_pd(y + k, _mm512_mask_i32gather_pd(zero, 0xFF, i, w.y, 8));
    _mm512_storeu_pd(ux + k, _mm512_mask_i32gather_pd(zero, 0xFF, i, w.ux, 8));
    _mm512_storeu_pd(uy + k, _mm512_mask_i32gather_pd(zero, 0xFF, i, w.uy, 8));
  }
#endif
  for (; k < hi; ++k) {
    const std::uint32_t i = id[k];
    x[k] = w.x[i];
    y[k] = w.y[i];
    ux[k] = w.ux[i];
    uy[k] = w.uy[i];
  }
}

// The same copy in float, for the float pre-test (step/float_pretest.hpp). Scalar: GCC turned
// the loop into AVX-512 gathers of the doubles, and sweep's build took a sixth longer with them
// (default scene, T = 1: broad phase 3.7 against 4.4 ms).
[[gnu::optimize("no-tree-vectorize")]] inline void copy_floats_in_order(
    const World& w, const std::uint32_t* id, std::size_t lo, std::size_t hi, float* x, float* y,
    float* ux, float* uy) {
  for (std::size_t k = lo; k < hi; ++k) {
    const std::uint32_t i = id[k];
    x[k] = static_cast<float>(w.x[i]);
    y[k] = static_cast<float>(w.y[i]);
    ux[k] = static_cast<float>(w.ux[i]);
    uy[k] = static_cast<float>(w.uy[i]);
  }
}

// Displacement statistics of one thread's share, combined in thread order (deterministic).
struct alignas(64) SpeedStats {
  double probe = INFINITY;  // count the particles faster than this
  double max = 0;           // largest axis_speed
  double sum = 0;           // sum of axis_speed (for the mean)
  double sum_abs_ux = 0, sum_abs_uy = 0;
  std::uint64_t count = 0;
  std::uint64_t above = 0;  // particles with axis_speed > probe

  void add(double ux, double uy) {
    const double ax = std::fabs(ux), ay = std::fabs(uy), a = std::max(ax, ay);
    max = std::max(max, a);
    sum += a;
    sum_abs_ux += ax;
    sum_abs_uy += ay;
    ++count;
    above += a > probe;
  }
  void merge(const SpeedStats& o) {
    max = std::max(max, o.max);
    sum += o.sum;
    sum_abs_ux += o.sum_abs_ux;
    sum_abs_uy += o.sum_abs_uy;
    count += o.count;
    above += o.above;
  }
  double mean() const { return count ? sum / static_cast<double>(count) : 0; }
};

#ifdef __AVX512F__
// SpeedStats::add on eight particles at a time, the sums in eight lanes: their rounding differs
// from one lane's by ulps, and the statistics only plan (a probe, a cell side), never a pair set.
struct SpeedLanes {
  __m512d probe, fastest = _mm512_setzero_pd(), sum = fastest, sum_ux = fastest, sum_uy = fastest;
  __m512i above = _mm512_setzero_si512();

  explicit SpeedLanes(double p) : probe(_mm512_set1_pd(p)) {}

  // ax, ay: |ux| and |uy| of eight particles.
  void add(__m512d ax, __m512d ay) {
    const __m512d a = _mm512_max_pd(ax, ay);
    fastest = _mm512_max_pd(fastest, a);
    sum = _mm512_add_pd(sum, a);
    sum_ux = _mm512_add_pd(sum_ux, ax);
    sum_uy = _mm512_add_pd(sum_uy, ay);
    above = _mm512_mask_add_epi64(above, _mm512_cmp_pd_mask(a, probe, _CMP_GT_OQ), above,
                                  _mm512_set1_epi64(1));
  }
  // Adds the lanes, which saw `count` particles, to s.
  void add_to(SpeedStats& s, std::uint64_t count) const {
    s.max = std::max(s.max, _mm512_reduce_max_pd(fastest));
    s.sum += _mm512_reduce_add_pd(sum);
    s.sum_abs_ux += _mm512_reduce_add_pd(sum_ux);
    s.sum_abs_uy += _mm512_reduce_add_pd(sum_uy);
    s.count += count;
    s.above += static_cast<std::uint64_t>(_mm512_reduce_add_epi64(above));
  }
};
#elif defined(__AVX2__)
// SpeedLanes on four particles at a time (AVX2).
struct SpeedLanes {
  __m256d probe, fastest = _mm256_setzero_pd(), sum = fastest, sum_ux = fastest, sum_uy = fastest;
  __m256i above = _mm256_setzero_si256();

  explicit SpeedLanes(double p) : probe(_mm256_set1_pd(p)) {}

  // ax, ay: |ux| and |uy| of four particles.
  void add(__m256d ax, __m256d ay) {
    const __m256d a = _mm256_max_pd(ax, ay);
    fastest = _mm256_max_pd(fastest, a);
    sum = _mm256_add_pd(sum, a);
    sum_ux = _mm256_add_pd(sum_ux, ax);
    sum_uy = _mm256_add_pd(sum_uy, ay);
    // A lane above the probe compares to all ones: -1.
    above = _mm256_sub_epi64(above, _mm256_castpd_si256(_mm256_cmp_pd(a, probe, _CMP_GT_OQ)));
  }
  // Adds the lanes, which saw `count` particles, to s.
  void add_to(SpeedStats& s, std::uint64_t count) const {
    alignas(32) double f[4], a[4], x[4], y[4];
    alignas(32) std::int64_t n[4];
    _mm256_store_pd(f, fastest);
    _mm256_store_pd(a, sum);
    _mm256_store_pd(x, sum_ux);
    _mm256_store_pd(y, sum_uy);
    _mm256_store_si256(reinterpret_cast<__m256i*>(n), above);
    for (int l = 0; l < 4; ++l) {
      s.max = std::max(s.max, f[l]);
      s.sum += a[l];
      s.sum_abs_ux += x[l];
      s.sum_abs_uy += y[l];
      s.above += static_cast<std::uint64_t>(n[l]);
    }
    s.count += count;
  }
};
#endif

// Adds the statistics of particles [first, last) of w to s. A pass of its own: folded into a
// per-particle loop that does more (the cells' binning), the statistics stayed in memory, each
// particle's maximum and sums waiting on the previous one's stores.
inline void add_speed_stats(const World& w, std::size_t first, std::size_t last, SpeedStats& s) {
  std::size_t i = first;
#ifdef __AVX512F__
  SpeedLanes lanes(s.probe);
  for (; last - i >= 8; i += 8)
    lanes.add(_mm512_abs_pd(_mm512_loadu_pd(w.ux + i)), _mm512_abs_pd(_mm512_loadu_pd(w.uy + i)));
  lanes.add_to(s, i - first);
#elif defined(__AVX2__)
  SpeedLanes lanes(s.probe);
  for (; last - i >= 4; i += 4)
    lanes.add(abs_lanes(_mm256_loadu_pd(w.ux + i)), abs_lanes(_mm256_loadu_pd(w.uy + i)));
  lanes.add_to(s, i - first);
#endif
  for (; i < last; ++i) s.add(w.ux[i], w.uy[i]);
}

// team: grows a per-thread vector to the team's size. Every thread has read the size before any
// passes the first barrier, so all agree whether to grow; after the first call it costs nothing.
template <class T>
void fit_to_team(std::vector<T>& per_thread) {
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  if (per_thread.size() < threads) {
    team_barrier();
    team_single([&] { per_thread.resize(threads); });
  }
}

// team, barrier at the end: the statistics of every particle's displacement.
inline SpeedStats team_speed_stats(const World& w, std::vector<SpeedStats>& slots,
                                   double probe = INFINITY) {
  const int t = omp_get_thread_num();
  team_single([&] { slots.assign(omp_get_num_threads(), SpeedStats{}); });
  SpeedStats mine;
  mine.probe = probe;
  const auto threads = static_cast<std::size_t>(omp_get_num_threads());
  add_speed_stats(w, w.n * t / threads, w.n * (t + 1) / threads, mine);
  slots[t] = mine;
  team_barrier();
  SpeedStats all;
  all.probe = probe;
  for (const SpeedStats& s : slots) all.merge(s);
  team_barrier();  // nobody may reuse the slots before everyone has read them
  return all;
}

// team, no barrier: the wall candidates of this sub-step, from the broad phase where it knows
// which particles can reach a wall line (cells kept across sub-steps), else from every particle.
template <class Broad>
void find_walls(const Broad& broad, const World& w, ThreadScratch& out) {
  if constexpr (requires { broad.find_wall_candidates(w, out); })
    broad.find_wall_candidates(w, out);
  else
    find_wall_candidates(w, out);
}

// team, no barrier: every piece of a broad phase's pair search (step/pipeline.hpp's BroadPhase),
// split by team_for, so a late thread leaves its pieces to the others.
template <class Broad>
void find_pairs(Broad& broad, const World& w, ThreadScratch& out) {
  team_for(broad.chunks(w), [&](std::uint32_t c) { broad.find_pairs_in(w, c, out); });
}

}  // namespace particle::detail
