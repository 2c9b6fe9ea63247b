#pragma once
// The pre-test in single precision: 16 pairs a register where flag_lanes8 (step/narrow_phase.hpp)
// takes 8 (with AVX2, 8 where it takes two registers of 4), for the spans of sweep and bands (the
// default scene's narrow phase is 96 million pairs of them). Each flagged pair then takes the exact
// test in double, on the World's own values (a broad phase that makes float copies makes no double
// ones), so the candidates are the exact test's; the float test only has to flag every pair that
// test can accept.
//
// Why it never drops a pair. Write D, W for the exact differences of two particles' doubles
// (d = x_j - x_i, w = u_j - u_i), P for a bound on every |coordinate| (positions stay in [0, L],
// docs/model.md: P = L) and V on every |velocity component|, u = 2^-24 (float's unit roundoff).
// 1. The exact test (pair_terms, pair_time, note_overlap) acts only where its computed c <= 0 or
//    disc > 0. Its double rounding (relative 2^-53 a product, a few per term) then leaves
//    |D| <= s + sigma or |cross(D, W)| <= |W| (s + sigma), with sigma = 2^-24 (s + 3P), far above
//    double's error (about 2^-25 (s + |D|)). The first implies the second (|cross(D, W)| <=
//    |D| |W|: a line passes no further from the origin than any point of it), so one test of the
//    line covers overlaps too: no test of the distance.
// 2. The float copies (each value within u of its double) give differences d_f, w_f with
//    |d_f - D| <= dd = 6uP and |w_f - W| <= dw = 6uV (per axis 4.01uP, times sqrt 2).
// 3. So |cross(d_f, w_f)| <= |cross(D, W)| + dd |w_f| + |D| dw
//    <= |w_f| (s + sigma + dd) + dw (s + sigma + 3P).
// 4. The float cross product itself (one product, one FMA) errs by at most
//    2.01u (|dx wy| + |dy wx|) <= 7uP |w_f|. With a = sigma + dd + 7uP and
//    b = dw (s + sigma + 3P): |cross_f| <= |w_f| (s + a) + b, whose square is at most
//    line |w_f|^2 + spread with line = (1 + 1/16) (s + a)^2 and spread = 17 b^2 (for any
//    theta > 0, (p + q)^2 <= (1 + theta) p^2 + (1 + 1/theta) q^2; theta = 1/16 widens the line's
//    reach by 3%).
// 5. The float squares and sums err by a few u relative; both constants are widened by 2^-16 and
//    rounded up to float, and 2^-60 is added to spread: where the float products underflow (tiny
//    velocities) their error is absolute, below 2^-140, far inside that.
// The pair is flagged if cross_f^2 <= line |w_f|^2 + spread (a pair with w_f = 0 always is: it may
// overlap). On the default scene (L = 20000, r = 1) a is about 0.02: the test reaches 1% beyond s.
// It applies where no float square overflows (s, P, V <= 2^26) and s >= 2^-20; elsewhere the
// double pre-test runs.
#include <algorithm>
#include <cmath>
#include <cstdint>

#if defined(__AVX512F__) || (defined(__AVX2__) && defined(__FMA__))
#include <immintrin.h>
// The float pre-tests run: 16 pairs a register with AVX-512, 8 with AVX2 and FMA (the same
// operations on half the lanes).
#define PARTICLE_FLOAT_PRETEST 1
#endif

#include "default_init.hpp"
#include "step/narrow_phase.hpp"

namespace particle::detail {

// The bounds of one sub-step's float pre-test (see above).
struct FloatPretest {
  float line = 0, spread = 0;

  // Where the bounds below hold (no float square overflows, s not below 2^-20), with AVX-512 or
  // AVX2 and FMA (PARTICLE_FLOAT_PRETEST): both float pre-tests, this and FloatSubStepPretest.
  static bool applies([[maybe_unused]] double s, [[maybe_unused]] double P,
                      [[maybe_unused]] double V) {
#ifdef PARTICLE_FLOAT_PRETEST
    return s >= 0x1p-20 && s <= 0x1p26 && P <= 0x1p26 && V <= 0x1p26;
#else
    return false;
#endif
  }

  FloatPretest(double s, double P, double V) {
    constexpr double u = 0x1p-24, widen = 1 + 0x1p-16;
    const double sigma = u * (s + 3 * P);
    const double a = sigma + 6 * u * P + 7 * u * P;
    const double b = 6 * u * V * (s + sigma + 3 * P);
    line = float_at_least((1 + 1.0 / 16) * (s + a) * (s + a) * widen);
    spread = float_at_least(17 * b * b * widen + 0x1p-60);
  }

  // The float nearest v from above.
  static float float_at_least(double v) {
    const auto f = static_cast<float>(v);
    return f < v ? std::nextafter(f, INFINITY) : f;
  }
};

// A broad phase's float copy of its double one (SpanArrays), position for position.
struct SpanFloats {
  const float* x;
  const float* y;
  const float* ux;
  const float* uy;
};

struct FloatParticle {
  float x, y, ux, uy;
};

// The pre-test of a slow scene's listed pairs (broad_phase/pair_list.hpp) in single precision:
// FloatPretest's line test and, as the double pre-test adds may_touch_within_substep
// (step/narrow_phase.hpp), a test of time, on records {x, y, ux, uy} of floats, 16 pairs a
// register. On the slow crowd the double pre-test's eight lanes, each filled from eight arrays by
// scalar loads and inserts, took 26 instructions a pair; two 16-byte loads a pair and a transpose
// take about ten.
//
// Why the test of time never drops a pair. D, W: the double differences pair_terms rounds
// (d = x_j - x_i in double); d, w: the float records' differences, rounded in float. Per axis
// |d - D| <= 3.01 uP + 2^-53 P (two copies within uP, the float subtraction within u 2P, the
// double one within 2^-53 P), so |d - D| <= dd = 6uP and likewise |w - W| <= dw = 6uV; e = dd + dw.
// 1. Every pair the exact test acts on passes may_touch_within_substep in double (its own
//    argument): one of T1 = |D|^2 - s^2, T2 = |D|^2 + D.W - s^2, T3 = |D + W|^2 - s^2, computed in
//    double, is at most 2^-20 (|D|^2 + |W|^2 + s^2). Their double rounding is below 2^-48 of
//    that, so in real arithmetic T_k(D, W) <= eps (|D|^2 + |W|^2 + s^2) with eps = 2^-19.
// 2. Each T_k is within 2 (|D| + |W|) e + e^2 of its value on (d, w) (expand the squares and the
//    product), and |D| + |W| <= |d| + |w| + e <= s / 2 + (|d|^2 + |w|^2) / s + e (for any k > 0,
//    sqrt(z) <= (k + z / k) / 2, here sqrt(2 (|d|^2 + |w|^2)) with k = s); |D|^2 + |W|^2 <=
//    2 (|d|^2 + |w|^2) + 2 e^2. So T_k(d, w) <= near0 + near1 (|d|^2 + |w|^2) with
//    near1 = 2 eps + 2 e / s and near0 = eps (s^2 + 2 e^2) + e s + 3 e^2.
// 3. The float computation of T_k (a square, a product, a sum each, relative u) and of
//    |d|^2 + |w|^2 errs by at most 10 u (|d|^2 + |w|^2 + s^2): 32 u is added to near1 and
//    32 u s^2 to near0, both widened by 2^-16 and rounded up to float. Where products underflow
//    (tiny velocities) their error, below 2^-140, is far inside near0 (at least 2^-59).
// A pair is flagged where FloatPretest's line test flags it and some computed T_k is at most
// near0 + near1 (|d|^2 + |w|^2): each is true of every pair the exact test acts on. On the
// million-particle scene (L = 4000, r = 1) the test reaches 0.2% beyond s.
struct FloatSubStepPretest {
  FloatPretest line;
  float s2, near0, near1;

  FloatSubStepPretest(double s, double P, double V) : line(s, P, V) {
    constexpr double u = 0x1p-24, eps = 0x1p-19, widen = 1 + 0x1p-16;
    const double e = 6 * u * (P + V);
    s2 = static_cast<float>(s * s);
    near1 = FloatPretest::float_at_least((2 * eps + 2 * e / s + 32 * u) * widen);
    near0 = FloatPretest::float_at_least(
        (eps * (s * s + 2 * e * e) + e * s + 3 * e * e + 32 * u * s * s) * widen);
  }

#ifdef __AVX512F__
  // Bit l set where lane l of the differences may meet within the sub-step (see above).
  [[gnu::always_inline]] unsigned flag16(__m512 dx, __m512 dy, __m512 wx, __m512 wy) const {
    const __m512 cross = _mm512_fmsub_ps(dx, wy, _mm512_mul_ps(dy, wx));
    const __m512 w2 = _mm512_fmadd_ps(wx, wx, _mm512_mul_ps(wy, wy));
    const __m512 reach =
        _mm512_fmadd_ps(w2, _mm512_set1_ps(line.line), _mm512_set1_ps(line.spread));
    const __mmask16 lined = _mm512_cmp_ps_mask(_mm512_mul_ps(cross, cross), reach, _CMP_LE_OQ);
    const __m512 d2 = _mm512_fmadd_ps(dx, dx, _mm512_mul_ps(dy, dy));
    const __m512 b = _mm512_fmadd_ps(dx, wx, _mm512_mul_ps(dy, wy));
    const __m512 slack =
        _mm512_fmadd_ps(_mm512_add_ps(d2, w2), _mm512_set1_ps(near1), _mm512_set1_ps(near0));
    const __m512 t1 = _mm512_sub_ps(d2, _mm512_set1_ps(s2));
    const __m512 t2 = _mm512_add_ps(t1, b);
    const __m512 t3 = _mm512_add_ps(_mm512_add_ps(t2, b), w2);
    return _mm512_mask_cmp_ps_mask(lined, _mm512_min_ps(_mm512_min_ps(t1, t2), t3), slack,
                                   _CMP_LE_OQ);
  }
#endif
#if defined(__AVX2__) && defined(__FMA__)
  // flag16 on eight lanes, the same operations in the same order: AVX2's compares write lanes
  // of all ones, one movemask takes their signs.
  [[gnu::always_inline]] unsigned flag8(__m256 dx, __m256 dy, __m256 wx, __m256 wy) const {
    const __m256 cross = _mm256_fmsub_ps(dx, wy, _mm256_mul_ps(dy, wx));
    const __m256 w2 = _mm256_fmadd_ps(wx, wx, _mm256_mul_ps(wy, wy));
    const __m256 reach =
        _mm256_fmadd_ps(w2, _mm256_set1_ps(line.line), _mm256_set1_ps(line.spread));
    const __m256 lined = _mm256_cmp_ps(_mm256_mul_ps(cross, cross), reach, _CMP_LE_OQ);
    const __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_mul_ps(dy, dy));
    const __m256 b = _mm256_fmadd_ps(dx, wx, _mm256_mul_ps(dy, wy));
    const __m256 slack =
        _mm256_fmadd_ps(_mm256_add_ps(d2, w2), _mm256_set1_ps(near1), _mm256_set1_ps(near0));
    const __m256 t1 = _mm256_sub_ps(d2, _mm256_set1_ps(s2));
    const __m256 t2 = _mm256_add_ps(t1, b);
    const __m256 t3 = _mm256_add_ps(_mm256_add_ps(t2, b), w2);
    const __m256 met = _mm256_cmp_ps(_mm256_min_ps(_mm256_min_ps(t1, t2), t3), slack, _CMP_LE_OQ);
    return static_cast<unsigned>(_mm256_movemask_ps(_mm256_and_ps(lined, met)));
  }
#endif
};

// Past its last particle a float copy must have this many readable entries: a group of 16 lanes
// reads up to 15 past the end of its span.
inline constexpr std::uint32_t kFloatSpanPadding = 16;

// What FloatGroups tests against: a broad phase's float copies, the World slot of each of their
// positions, the World's own arrays for the exact test of the few flagged pairs (a broad phase
// with float copies keeps no double ones), and where the results go.
struct Span {
  SpanArrays world;  // world_arrays()
  const std::uint32_t* id;
  SpanFloats af;
  FloatPretest t;
  double s2;
  ThreadScratch* out;
};

// The flagged lanes of a float group, row at position k and lanes from position j, through the
// exact test on the World's doubles (bit for bit the values the copies were made of). Out of
// line: rare, and it keeps the groups' loop small.
[[gnu::noinline]] inline void test_flagged_slots(const Span& span, std::uint32_t k, std::uint32_t j,
                                                 unsigned flagged) {
  const std::uint32_t i = span.id[k];
  const SpanArrays& a = span.world;
  const RowParticle p{a.x[i], a.y[i], a.ux[i], a.uy[i], i};
  for (; flagged != 0; flagged &= flagged - 1) {
    const std::uint32_t slot = span.id[j + static_cast<std::uint32_t>(__builtin_ctz(flagged))];
    test_copy_pair(p, a, slot, slot, span.s2, *span.out);
  }
}

#ifdef PARTICLE_FLOAT_PRETEST
#ifdef __AVX512F__
// Lanes a group of the float pre-test: one register.
inline constexpr std::uint32_t kFloatLanes = 16;

// Bit l set where lanes k + l of `a` may meet p (see above). Explicit FMAs: their single rounding
// is within the bounds above, and -ffp-contract=off only keeps the compiler from contracting.
// (FLOPS: 8 and 3 FMA, compares: 1)
[[gnu::always_inline]] inline unsigned flag_floats(const FloatParticle& p, const SpanFloats& a,
                                                   std::uint32_t k, const FloatPretest& t) {
  const __m512 dx = _mm512_sub_ps(_mm512_loadu_ps(a.x + k), _mm512_set1_ps(p.x));
  const __m512 dy = _mm512_sub_ps(_mm512_loadu_ps(a.y + k), _mm512_set1_ps(p.y));
  const __m512 wx = _mm512_sub_ps(_mm512_loadu_ps(a.ux + k), _mm512_set1_ps(p.ux));
  const __m512 wy = _mm512_sub_ps(_mm512_loadu_ps(a.uy + k), _mm512_set1_ps(p.uy));
  const __m512 cross = _mm512_fmsub_ps(dx, wy, _mm512_mul_ps(dy, wx));
  const __m512 w2 = _mm512_fmadd_ps(wx, wx, _mm512_mul_ps(wy, wy));
  const __m512 reach = _mm512_fmadd_ps(w2, _mm512_set1_ps(t.line), _mm512_set1_ps(t.spread));
  return _mm512_cmp_ps_mask(_mm512_mul_ps(cross, cross), reach, _CMP_LE_OQ);
}
#else
inline constexpr std::uint32_t kFloatLanes = 8;

// The same on eight lanes (AVX2 and FMA).
[[gnu::always_inline]] inline unsigned flag_floats(const FloatParticle& p, const SpanFloats& a,
                                                   std::uint32_t k, const FloatPretest& t) {
  const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(a.x + k), _mm256_set1_ps(p.x));
  const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(a.y + k), _mm256_set1_ps(p.y));
  const __m256 wx = _mm256_sub_ps(_mm256_loadu_ps(a.ux + k), _mm256_set1_ps(p.ux));
  const __m256 wy = _mm256_sub_ps(_mm256_loadu_ps(a.uy + k), _mm256_set1_ps(p.uy));
  const __m256 cross = _mm256_fmsub_ps(dx, wy, _mm256_mul_ps(dy, wx));
  const __m256 w2 = _mm256_fmadd_ps(wx, wx, _mm256_mul_ps(wy, wy));
  const __m256 reach = _mm256_fmadd_ps(w2, _mm256_set1_ps(t.line), _mm256_set1_ps(t.spread));
  return static_cast<unsigned>(
      _mm256_movemask_ps(_mm256_cmp_ps(_mm256_mul_ps(cross, cross), reach, _CMP_LE_OQ)));
}
#endif

// Spans as one stream of groups of kFloatLanes: each group carries its row k, its first position
// and its span's end, and the groups of many rows run in one loop. Row by row, the exit of each
// span's loop (about 6 groups of 16 on the default scene, a different count every row) was a
// mispredicted branch per particle, and it took as long as the groups themselves. Every span
// takes the groups, however short: a span of up to 8 through the double pre-test instead cost a
// branch a row that the bands' spans (about 19 long) missed often (bands' loop 12 to 18% slower,
// sweep's 2%).
class FloatGroups {
 public:
  // Adds the span [begin, end) of row k, begin <= end, to a stream of `size` groups and returns
  // its new size: the caller's loop keeps it in a register (a member, it went through memory at
  // every row, the stream's stores might have written it). The groups start at multiples of
  // kFloatLanes (16 floats on a cache line, LineAligned copies; 8 on half of one), the first
  // one's lanes below `begin` dead: a group that straddled two lines cost a sixth more than the
  // lanes this wastes. A group's entry is its first live position, the group itself starts at
  // that rounded down. Pieces of up to 16 groups: each piece writes sixteen groups' entries
  // whatever its length, and the stream grows by the groups it needs (an empty span by none). A
  // full stream is tested first.
  std::uint32_t add(std::uint32_t size, std::uint32_t k, std::uint32_t begin, std::uint32_t end,
                    const Span& span) {
    for (;;) {
      if (size > kCapacity - 16) size = test(size, span);
      const std::uint32_t base = begin & ~(kFloatLanes - 1);
      const std::uint32_t piece_end = end - base > kPiece ? base + kPiece : end;
#ifdef __AVX512F__
      _mm512_storeu_si512(row_ + size, _mm512_set1_epi32(static_cast<int>(k)));
      const __m512i starts = _mm512_add_epi32(_mm512_set1_epi32(static_cast<int>(base)),
                                              _mm512_setr_epi32(0, 16, 32, 48, 64, 80, 96, 112, 128,
                                                                144, 160, 176, 192, 208, 224, 240));
      _mm512_storeu_si512(begin_ + size,
                          _mm512_mask_set1_epi32(starts, 1, static_cast<int>(begin)));
      _mm512_storeu_si512(end_ + size, _mm512_set1_epi32(static_cast<int>(piece_end)));
#else
      const auto store2 = [](std::uint32_t* to, __m256i low, __m256i high) {
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(to), low);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(to + 8), high);
      };
      const __m256i row = _mm256_set1_epi32(static_cast<int>(k));
      store2(row_ + size, row, row);
      const __m256i starts = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(base)),
                                              _mm256_setr_epi32(0, 8, 16, 24, 32, 40, 48, 56));
      store2(begin_ + size,
             _mm256_blend_epi32(starts, _mm256_set1_epi32(static_cast<int>(begin)), 1),
             _mm256_add_epi32(starts, _mm256_set1_epi32(64)));
      const __m256i stop = _mm256_set1_epi32(static_cast<int>(piece_end));
      store2(end_ + size, stop, stop);
#endif
      size += piece_end > begin ? (piece_end - base + kFloatLanes - 1) / kFloatLanes : 0;
      if (piece_end == end) return size;
      begin = piece_end;
    }
  }

  // The first `size` groups through the float pre-test, the flagged pairs through the exact one;
  // returns the emptied stream's size, 0.
  std::uint32_t test(std::uint32_t size, const Span& span) {
    // Copies: through the reference, the loop reloaded every pointer at every group (the exact
    // test's call might have changed them).
    const SpanFloats af = span.af;
    const FloatPretest t = span.t;
    for (std::uint32_t g = 0; g < size; ++g) {
      const std::uint32_t k = row_[g], first = begin_[g], j = first & ~(kFloatLanes - 1);
      const FloatParticle pf{af.x[k], af.y[k], af.ux[k], af.uy[k]};
      const unsigned live =
          ((1u << std::min(end_[g] - j, kFloatLanes)) - 1) & ~((1u << (first - j)) - 1);
      if (const unsigned f = flag_floats(pf, af, j, t) & live) test_flagged_slots(span, k, j, f);
    }
    return 0;
  }

 private:
  static constexpr std::uint32_t kPiece = 16 * kFloatLanes, kCapacity = 512;

  std::uint32_t row_[kCapacity], begin_[kCapacity], end_[kCapacity];
};
#endif

// Rows [k_begin, k_end) of a sorting broad phase's order (copies.id: the World slot at each
// position), row k against the positions span_of(k) = {begin, end}, begin <= end: in float groups
// on the float copies where the float pre-test applies (pretest not null), else through
// test_span's double pre-test and its test of time on the double copies (kept only then).
template <class SpanOf>
void test_rows(const World& w, const SpanArrays& copies, [[maybe_unused]] const SpanFloats& floats,
               [[maybe_unused]] const FloatPretest* pretest, std::uint32_t k_begin,
               std::uint32_t k_end, ThreadScratch& out, SpanOf span_of) {
#ifdef PARTICLE_FLOAT_PRETEST
  if (pretest) {
    const Span span{world_arrays(w), copies.id, floats, *pretest, w.s2, &out};
    FloatGroups groups;
    std::uint32_t size = 0;
    std::uint64_t tests = 0;
    for (std::uint32_t k = k_begin; k < k_end; ++k) {
      const auto [begin, end] = span_of(k);
      tests += end - begin;
      size = groups.add(size, k, begin, end, span);
    }
    groups.test(size, span);
    out.pair_tests += tests;
    return;
  }
#endif
  const SpanArrays& a = copies;
  for (std::uint32_t k = k_begin; k < k_end; ++k) {
    const auto [begin, end] = span_of(k);
    test_span<true>({a.x[k], a.y[k], a.ux[k], a.uy[k], a.id[k]}, a, begin, end, w.s2, out);
  }
}

}  // namespace particle::detail
