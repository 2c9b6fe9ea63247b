#pragma once
// Narrow phase: the exact pair test of docs/model.md, "The model", step 2.
//
// Every engine calls these functions, so the candidate set is the same whatever the broad phase.
// The test is symmetric: swapping i and j negates d and w, which leaves b, c and disc
// bit-identical, so callers may pass a pair in either order; candidates are always emitted as (min,
// max).
//
// Cost: brute's rows and the long spans of the other broad phases (sweep's) take one pre-test,
// flag_lanes8, 8 lanes at a time (one AVX-512 register per term; 14 flops and 2 compares a pair;
// -ffp-contract=off keeps its rounding equal to the scalar test's) whose lane mask goes straight
// to a general register; in the rare groups with a flagged lane, only the flagged pairs take the
// exact scalar test, which alone takes a square root and a division.
#include <algorithm>
#include <cstdint>
#include <cstring>

#ifdef __AVX__
#include <immintrin.h>
#endif

#include "contact.hpp"
#include "world.hpp"

namespace particle::detail {

// The vectorized pre-test of short spans (test_span_group): true for every pair that pair_time
// accepts or that overlaps (c < 0), computed from the same rounded products. It compares the
// minuends of c and disc instead of subtracting (fl(a - b) <= 0 exactly when a <= b), saving two
// flops a pair. (FLOPS: 13) T is double (a bool-valued int) or Lanes4 (a lane mask, 0 or -1 per
// lane).
template <class T>
inline auto needs_exact_test(T dx, T dy, T wx, T wy, double s2) {
  const T b = dx * wx + dy * wy;
  const T d2 = dx * dx + dy * dy;
  const T cross = dx * wy - dy * wx;
  const T as2 = (wx * wx + wy * wy) * s2;
  return (d2 < s2) | ((b < 0) & ((d2 <= s2) | (as2 > cross * cross)));
}

// Four doubles in one AVX2 register, written with the GCC/Clang vector extension: element-wise
// IEEE arithmetic, so the same rounding as the scalar code (-ffp-contract=off: no FMA either).
// The compiler's own vectorization of a 4-lane loop used two 2-lane registers and twice the
// instructions.
using Lanes4 = double __attribute__((vector_size(32)));

inline Lanes4 load_lanes(const double* p) {
  Lanes4 v;
  std::memcpy(&v, p, sizeof v);  // one unaligned load
  return v;
}

// Bit l set where lane l of a comparison mask (four 64-bit lanes, each all ones or zero; eight
// with AVX-512) is set. With AVX one movemask of the lanes' sign bits: lane by lane, GCC
// assembled the bits through shuffles and a horizontal OR.
template <class Mask>
[[gnu::always_inline]] inline unsigned lane_bits(const Mask& m) {
#ifdef __AVX512F__
  if constexpr (sizeof(Mask) == 64)
    return _mm512_cmplt_epi64_mask(reinterpret_cast<__m512i>(m), _mm512_setzero_si512());
  else
#endif
  {
    static_assert(sizeof(Mask) == 32, "four 64-bit lanes");
#ifdef __AVX__
    return static_cast<unsigned>(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
#else
    return static_cast<unsigned>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8));
#endif
  }
}

// An overlap (c < 0) of particles i and j found by the exact test: counted, and its depth
// (s - distance)/s = 1 - sqrt(1 + c/s^2) kept if deepest; a receding one is kept apart as a
// candidate at t = 0, which the overlap reading `always` takes (split_contested). Rare, so the
// square root costs nothing in the common case; a maximum is order-free, so every engine and
// thread count finds the same one.
inline void note_overlap(const PairTerms& terms, double s2, std::uint32_t i, std::uint32_t j,
                         ThreadScratch& out) {
  if (terms.c >= 0) return;
  ++out.overlaps;
  out.max_overlap = std::max(out.max_overlap, overlap_depth(terms.c, s2));
  if (terms.b >= 0) {
    ++out.receding_overlaps;
    out.receding.push_back({0.0, std::min(i, j), std::max(i, j)});
  }
}

// One particle's values, copied bit for bit from the World, and its World id.
struct RowParticle {
  double x, y, ux, uy;
  std::uint32_t id;
};

// Particles in a broad phase's order (cell or sweep order) with the World ids they stand for:
// neighbours that are scattered in the World are contiguous here. The World itself is one such
// array in its own order, without ids (position k is id k).
struct SpanArrays {
  const double* x;
  const double* y;
  const double* ux;
  const double* uy;
  const std::uint32_t* id;  // nullptr in world_arrays()
};

inline SpanArrays world_arrays(const World& w) { return {w.x, w.y, w.ux, w.uy, nullptr}; }

inline RowParticle world_particle(const World& w, std::uint32_t i) {
  return {w.x[i], w.y[i], w.ux[i], w.uy[i], i};
}

// The exact test of p against position k of `a` (d = p_k - p), whose World id is j: counts an
// overlap, emits a candidate. The one scalar pair test of every discrete engine.
inline void test_copy_pair(const RowParticle& p, const SpanArrays& a, std::uint32_t k,
                           std::uint32_t j, double s2, ThreadScratch& out) {
  const PairTerms terms =
      pair_terms(a.x[k] - p.x, a.y[k] - p.y, a.ux[k] - p.ux, a.uy[k] - p.uy, s2);
  note_overlap(terms, s2, p.id, j, out);
  double t;
  if (pair_time(terms, t)) out.candidates.push_back({t, std::min(p.id, j), std::max(p.id, j)});
}

// The exact test of World particles i and j.
inline void test_pair(const World& w, std::uint32_t i, std::uint32_t j, ThreadScratch& out) {
  test_copy_pair(world_particle(w, i), world_arrays(w), j, j, w.s2, out);
}

// A broad phase's copy must have this many readable entries past its last particle: an 8-lane
// group reads up to 7 past the end of its span.
inline constexpr std::uint32_t kSpanPadding = 8;

// The pre-test's lane masks: bit l set where lane l of `a` is below (or at most) lane l of `b`.
// Four lanes: with AVX one compare and one movemask, else lane by lane.
template <bool OrEqual>
[[gnu::always_inline]] inline unsigned lanes_below(const Lanes4& a, const Lanes4& b) {
#ifdef __AVX__
  return static_cast<unsigned>(
      _mm256_movemask_pd(_mm256_cmp_pd(reinterpret_cast<__m256d>(a), reinterpret_cast<__m256d>(b),
                                       OrEqual ? _CMP_LE_OQ : _CMP_LT_OQ)));
#else
  return lane_bits(OrEqual ? a <= b : a < b);
#endif
}

#ifdef __AVX512F__
// Eight doubles: one AVX-512 register, whose comparison writes a mask register that moves to a
// general register in one instruction. (Without AVX-512 the pre-test takes two Lanes4 instead:
// GCC's lowering of 64-byte vectors to AVX2 broadcast each scalar through the stack, a
// store-forwarding stall per group, 5 times as long on grid's spans.)
using Lanes8 = double __attribute__((vector_size(64)));

// The 8 lanes from p on (one unaligned load).
[[gnu::always_inline]] inline Lanes8 load_lanes8(const double* p) {
  Lanes8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <bool OrEqual>
[[gnu::always_inline]] inline unsigned lanes_below(const Lanes8& a, const Lanes8& b) {
  return _mm512_cmp_pd_mask(reinterpret_cast<__m512d>(a), reinterpret_cast<__m512d>(b),
                            OrEqual ? _CMP_LE_OQ : _CMP_LT_OQ);
}

[[gnu::always_inline]] inline Lanes8 load_group(const double* p, Lanes8) { return load_lanes8(p); }
#endif

[[gnu::always_inline]] inline Lanes4 load_group(const double* p, Lanes4) { return load_lanes(p); }

// The pre-test on the lanes of one V from k: bit l set for every pair that pair_time accepts or
// that overlaps, from the same rounded products as pair_terms. A candidate either touches now
// (c <= 0, exactly fl(dx^2 + dy^2) <= s2) or has disc > 0, and fl(as2 - cc) > 0 exactly when
// as2 > cc. It leaves out the sign of b: receding pairs whose line passes within s are about as
// rare as approaching ones, and their exact test costs less than 4 operations on every pair
// (brute's rows). The squared distance cannot be cut to dx^2: a sweep's spans are x-neighbours,
// and in a crowd nearly all of them have |dx| <= s.  (FLOPS: 14, compares: 2)
template <class V>
[[gnu::always_inline]] inline unsigned flag_group(const RowParticle& p, const SpanArrays& a,
                                                  std::uint32_t k, double s2) {
  const V dx = load_group(a.x + k, V{}) - p.x, dy = load_group(a.y + k, V{}) - p.y;
  const V wx = load_group(a.ux + k, V{}) - p.ux, wy = load_group(a.uy + k, V{}) - p.uy;
  const V cross = dx * wy - dy * wx;
  const V as2 = (wx * wx + wy * wy) * s2;
  return lanes_below<false>(cross * cross, as2) | lanes_below<true>(dx * dx + dy * dy, V{} + s2);
}

// The pre-test on lanes k .. k+7 of `a`: one AVX-512 register, or two of four lanes.
[[gnu::always_inline]] inline unsigned flag_lanes8(const RowParticle& p, const SpanArrays& a,
                                                   std::uint32_t k, double s2) {
#ifdef __AVX512F__
  return flag_group<Lanes8>(p, a, k, s2);
#else
  return flag_group<Lanes4>(p, a, k, s2) | flag_group<Lanes4>(p, a, k + 4, s2) << 4;
#endif
}

// Two groups: 16 lanes from k, one branch on both masks. The pre-test's helpers are always
// inlined: a call would pass 64-byte vectors through memory.
[[gnu::always_inline]] inline unsigned flag_lanes16(const RowParticle& p, const SpanArrays& a,
                                                    std::uint32_t k, double s2) {
  return flag_lanes8(p, a, k, s2) | flag_lanes8(p, a, k + 8, s2) << 8;
}

// The flagged lanes from k on through the exact test. Out of line: rare, and it keeps the loops
// over lanes small.
[[gnu::noinline]] inline void test_flagged(const RowParticle& p, const SpanArrays& a,
                                           std::uint32_t k, unsigned flagged, double s2,
                                           ThreadScratch& out) {
  for (; flagged != 0; flagged &= flagged - 1) {
    const std::uint32_t l = k + static_cast<std::uint32_t>(__builtin_ctz(flagged));
    test_copy_pair(p, a, l, a.id ? a.id[l] : l, s2, out);
  }
}

// p against every k in [k_begin, k_end) of a broad phase's copy (kSpanPadding readable past the
// end), 8 lanes at a time, the last group with its dead lanes masked: a span has no branch but
// its loop's.
[[gnu::always_inline]] inline void test_copy_run(const RowParticle& p, const SpanArrays& a,
                                                 std::uint32_t k_begin, std::uint32_t k_end,
                                                 double s2, ThreadScratch& out) {
  std::uint32_t k = k_begin;
  for (; k_end - k > 8; k += 8)
    if (const unsigned f = flag_lanes8(p, a, k, s2)) test_flagged(p, a, k, f, s2, out);
  const unsigned f = flag_lanes8(p, a, k, s2) & ((1u << (k_end - k)) - 1);
  if (f) test_flagged(p, a, k, f, s2, out);
}

// p against every k in [k_begin, k_end) of the World's own arrays (nothing readable past n), 16
// lanes at a time; then a group of 8 if 8 are left, then the 8 entries that end at k_end with the
// lanes already tested masked, or pair by pair in a World of fewer than 8. Always inlined into
// brute's row loop: out of line, the same loop took 1.6 times as long (bench_engine's
// BM_TestRowAllPairs); 16 lanes an iteration took 0.8 times as long as 8. Spans are shorter:
// there 16 lanes did not pay (test_copy_run).
[[gnu::always_inline]] inline void test_world_run(const RowParticle& p, const SpanArrays& a,
                                                  std::uint32_t k_begin, std::uint32_t k_end,
                                                  double s2, ThreadScratch& out) {
  std::uint32_t k = k_begin;
  for (; k_end - k >= 16; k += 16)
    if (const unsigned f = flag_lanes16(p, a, k, s2)) test_flagged(p, a, k, f, s2, out);
  if (k_end - k >= 8) {
    if (const unsigned f = flag_lanes8(p, a, k, s2)) test_flagged(p, a, k, f, s2, out);
    k += 8;
  }
  const std::uint32_t rest = k_end - k;
  if (rest == 0) return;
  if (k_end >= 8) {
    const unsigned f = flag_lanes8(p, a, k_end - 8, s2) & (0xFFu << (8 - rest)) & 0xFFu;
    if (f) test_flagged(p, a, k_end - 8, f, s2, out);
  } else {
    test_flagged(p, a, k, (1u << rest) - 1, s2, out);
  }
}

// Tests particle i against every j in [j_begin, j_end) of the world's arrays.
inline void test_row(const World& w, std::uint32_t i, std::uint32_t j_begin, std::uint32_t j_end,
                     ThreadScratch& out) {
  test_world_run(world_particle(w, i), world_arrays(w), j_begin, j_end, w.s2, out);
  out.pair_tests += j_end - j_begin;
}

// Whether a pair at squared distance d2, with b = d.w and squared relative displacement a, that
// needs_exact_test flags meets within the sub-step: the line test ignores time, so in slow
// scenes it flags many approaching pairs that meet only sub-steps later (on the million-particle
// scene one per particle and sub-step, each an exact test with a square root and a division).
// With c = d2 - s2 > 0 and disc > 0, pair_time's root c / (-b + sqrt(disc)) is at most 1 exactly
// when c + b <= sqrt(disc): when c + b <= 0, or else, squaring (disc = b^2 - a c), when
// c (c + 2b + a) <= 0, that is |d + w|^2 <= s^2 (touching at the sub-step's end). So the pair
// passes if c <= 0 (an overlap, always tested), c + b <= 0 or c + 2b + a <= 0, each against a
// slack of 2^-20 (d2 + a + s2): the rounding of these terms and of pair_time's own (its disc's
// error over c, where c passes the first test, stays below 10^-10 a) is far smaller, so no pair
// that pair_time accepts is dropped. It asks |d + w t| <= s for some t in [0, 1], where the
// bound it replaced asked d^2 <= 2 (s^2 + |w|^2), which in a slow scene lets pairs up to about
// 1.4 s apart through, many sub-steps from contact: on the million-particle scene (cells, T = 1,
// 2-core AMD EPYC VM) the narrow phase went from 0.29-0.30 s to 0.21-0.23 s, the exact test from
// 6.6% to 2.8% of the process. In a sparse scene, where the line test flags few pairs, the six
// flops more a lane are a cost without a gain (the slow crowd's instructions +1.2%, its time the
// same); taking them only for a group with a lane flagged gave the million scene's time back to
// the branch (narrow phase 0.23 -> 0.29 s).  (FLOPS: 8)
template <class T>
inline auto may_touch_within_substep(T d2, T b, T a, double s2) {
  const T c = d2 - s2;
  const T slack = (d2 + a + s2) * 0x1p-20;
  return (c <= slack) | (c + b <= slack) | (c + (b + b) + a <= slack);
}

// Up to B live lanes from k0, B = 4 or 8 (one or two Lanes4): only the flagged lanes are
// rescanned (in dense scenes many pairs of a short span are flagged, and each rescan costs a
// square root and a division). Short spans are the cells' (about one particle per cell), where
// the displacement is small next to the distance, so the group also applies
// may_touch_within_substep.
template <std::uint32_t B>
inline void test_span_group(const RowParticle& p, const SpanArrays& a, std::uint32_t k0,
                            std::uint32_t live, double s2, ThreadScratch& out) {
  unsigned flagged = 0;  // bit l: lane l needs the exact test
  for (std::uint32_t q = 0; q < B; q += 4) {
    const std::uint32_t k = k0 + q;
    const Lanes4 dx = load_lanes(a.x + k) - p.x, dy = load_lanes(a.y + k) - p.y;
    const Lanes4 wx = load_lanes(a.ux + k) - p.ux, wy = load_lanes(a.uy + k) - p.uy;
    flagged |= lane_bits(needs_exact_test(dx, dy, wx, wy, s2) &
                         may_touch_within_substep(dx * dx + dy * dy, dx * wx + dy * wy,
                                                  wx * wx + wy * wy, s2))
               << q;
  }
  flagged &= (1u << live) - 1;                  // live <= 8
  for (; flagged != 0; flagged &= flagged - 1)  // no candidate or overlap in unflagged lanes
  {
    const std::uint32_t k = k0 + static_cast<std::uint32_t>(__builtin_ctz(flagged));
    test_copy_pair(p, a, k, a.id[k], s2, out);
  }
}

// Up to 8 live lanes from k0: one Lanes4 when they fit.
inline void test_short_span(const RowParticle& p, const SpanArrays& a, std::uint32_t k0,
                            std::uint32_t live, double s2, ThreadScratch& out) {
  if (live <= 4)
    test_span_group<4>(p, a, k0, live, s2, out);
  else
    test_span_group<8>(p, a, k0, live, s2, out);
}

// test_copy_run out of line: inlined into the cells' stencil loops it made the crowd's pair search
// 10% slower (bench_engine's BM_BroadAndNarrow/cells/crowd).
[[gnu::noinline]] inline void test_long_span(const RowParticle& p, const SpanArrays& a,
                                             std::uint32_t k_begin, std::uint32_t k_end, double s2,
                                             ThreadScratch& out) {
  test_copy_run(p, a, k_begin, k_end, s2, out);
}

// test_row over a broad phase's copy: particle p against every k in [k_begin, k_end) of `a`.
// The arithmetic is the same functions on the same bits (d = p_k - p), so the candidates, their
// times and the overlap count are exactly those of test_row/test_pair on the World's ids.
// Spans of up to 8 (the cells' at about one particle per cell) take one or two Lanes4, longer ones
// test_copy_run; they read up to 7 entries past k_end, hence kSpanPadding (the extra lanes are
// computed and ignored). InlineLong: test_copy_run inlined into the caller's loop (sweep's: 12%
// less time per pair test on the default scene) instead of called.
template <bool InlineLong = false>
inline void test_span(const RowParticle& p, const SpanArrays& a, std::uint32_t k_begin,
                      std::uint32_t k_end, double s2, ThreadScratch& out) {
  if (k_end <= k_begin) return;
  const std::uint32_t live = k_end - k_begin;
  out.pair_tests += live;
  if (live <= 8)
    test_short_span(p, a, k_begin, live, s2, out);
  else if constexpr (InlineLong)
    test_copy_run(p, a, k_begin, k_end, s2, out);
  else
    test_long_span(p, a, k_begin, k_end, s2, out);
}

}  // namespace particle::detail
