#pragma once
// Narrow phase: the exact pair test of docs/model.md, "The model", step 2.
//
// Every engine calls these functions, so the candidate set is the same whatever the broad phase.
// The test is symmetric: swapping i and j negates d and w, which leaves b, c and disc
// bit-identical, so callers may pass a pair in either order; candidates are always emitted as (min,
// max).
//
// Cost: test_row is a branch-free loop over j (13 flops a pair, vectorized; -ffp-contract=off keeps
// its rounding equal to the scalar test's) that only counts the pairs that could collide or
// overlap; in the rare blocks with a hit, only the flagged pairs take the exact scalar test, which
// alone takes a square root and a division.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "world.hpp"

namespace particle::detail {

struct PairTerms {
  double b, c, disc;
};

// d = p_j - p_i, w = u_j - u_i. disc uses Lagrange's identity a*s^2 - (d x w)^2 instead of
// b^2 - a*c, which would cancel the large |d|^2 |w|^2 terms.  (FLOPS: 15)
inline PairTerms pair_terms(double dx, double dy, double wx, double wy, double s2) {
  const double b = dx * wx + dy * wy;
  const double c = dx * dx + dy * dy - s2;
  const double cross = dx * wy - dy * wx;
  const double disc = (wx * wx + wy * wy) * s2 - cross * cross;
  return {b, c, disc};
}

// The time of contact from now, in the units of w, if the pair ever meets on straight lines:
// approaching and overlapping collide at t = 0; receding (even overlapping) or grazing never
// (infinity); otherwise the smaller root in its stable form c / (-b + sqrt(disc)). The one root
// arithmetic of the lab: the discrete engines bound it to the sub-step (pair_time), the event
// engine does not. Selects instead of branches: the event engine tests every neighbour, and
// whether a pair meets is a coin toss to a branch predictor. (The root of a pair that does not
// meet is computed and dropped; max keeps sqrt off negative numbers, which would set errno
// through a library call.)
inline double contact_time(const PairTerms& p) {
  const double root = p.c / (-p.b + std::sqrt(std::max(p.disc, 0.0)));
  const double t = p.c <= 0 ? 0.0 : (p.disc > 0 ? root : std::numeric_limits<double>::infinity());
  return p.b < 0 ? t : std::numeric_limits<double>::infinity();
}

// The time of contact within the sub-step, if any; touching at t = 1 counts.
inline bool pair_time(const PairTerms& p, double& t) {
  t = contact_time(p);
  return t <= 1;
}

// The vectorized pre-test of test_row: true for every pair that pair_time accepts or that
// overlaps (c < 0), computed from the same rounded products. It compares the minuends of c and
// disc instead of subtracting (fl(a - b) <= 0 exactly when a <= b), saving two flops a pair.
// (FLOPS: 13) T is double (a bool-valued int) or Lanes4 (a lane mask, 0 or -1 per lane).
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

// Bit l set where lane l of a comparison mask is set.
template <class Mask>
inline unsigned lane_bits(const Mask& m) {
  return static_cast<unsigned>((m[0] & 1) | (m[1] & 2) | (m[2] & 4) | (m[3] & 8));
}

// An overlap (c < 0) found by the exact test: counted, and its depth (s - distance)/s =
// 1 - sqrt(1 + c/s^2) kept if deepest. Rare, so the square root costs nothing in the common case;
// a maximum is order-free, so every engine and thread count finds the same one.
inline void note_overlap(double c, double s2, ThreadScratch& out) {
  if (c >= 0) return;
  ++out.overlaps;
  out.max_overlap = std::max(out.max_overlap, 1 - std::sqrt(1 + c / s2));
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
  note_overlap(terms.c, s2, out);
  double t;
  if (pair_time(terms, t)) out.candidates.push_back({t, std::min(p.id, j), std::max(p.id, j)});
}

// The exact test of World particles i and j.
inline void test_pair(const World& w, std::uint32_t i, std::uint32_t j, ThreadScratch& out) {
  test_copy_pair(world_particle(w, i), world_arrays(w), j, j, w.s2, out);
}

// A broad phase's copy must have this many readable entries past its last particle.
inline constexpr std::uint32_t kSpanPadding = 64;

// Lanes of `a` from k0 through the vector pre-test; if any is flagged, the flagged ones take the
// exact test. B > 0: B lanes of a broad phase's copy, the first `live` of them real (Masked) or
// all of them (fixed-length vector loops, one reduction); B = 0: exactly `live` lanes (at most
// kSpanPadding) of the World's own arrays, no reads past them.
template <std::uint32_t B, bool Masked>
inline void test_span_block(const RowParticle& p, const SpanArrays& a, std::uint32_t k0,
                            std::uint32_t live, double s2, ThreadScratch& out) {
  const std::uint32_t lanes = B > 0 ? B : live;
  const double* __restrict xs = a.x + k0, * __restrict ys = a.y + k0;
  const double* __restrict uxs = a.ux + k0, * __restrict uys = a.uy + k0;
  std::int64_t hits = 0;
  for (std::uint32_t l = 0; l < lanes; ++l) {
    const bool flagged =
        needs_exact_test(xs[l] - p.x, ys[l] - p.y, uxs[l] - p.ux, uys[l] - p.uy, s2);
    hits += Masked ? ((l < live) & flagged) : flagged;
  }
  if (hits == 0) return;
  // Rare: flag the lanes again (vectorized) and take only the flagged ones through the exact
  // test and its square root.
  std::uint8_t flag[B > 0 ? B : kSpanPadding];
  for (std::uint32_t l = 0; l < lanes; ++l)
    flag[l] = (!Masked || l < live) &
              needs_exact_test(xs[l] - p.x, ys[l] - p.y, uxs[l] - p.ux, uys[l] - p.uy, s2);
  for (std::uint32_t l = 0; l < lanes; ++l)
    if (flag[l]) test_copy_pair(p, a, k0 + l, B > 0 ? a.id[k0 + l] : k0 + l, s2, out);
}

// Tests particle i against every j in [j_begin, j_end) of the world's arrays, in blocks of 64
// (short enough that a rescan is cheap); the World has no padding, so the last block is exact.
inline void test_row(const World& w, std::uint32_t i, std::uint32_t j_begin, std::uint32_t j_end,
                     ThreadScratch& out) {
  const SpanArrays a = world_arrays(w);
  const RowParticle p = world_particle(w, i);
  for (std::uint32_t j0 = j_begin; j0 < j_end; j0 += kSpanPadding)
    test_span_block<0, false>(p, a, j0, std::min(j_end - j0, kSpanPadding), w.s2, out);
  out.pair_tests += j_end - j_begin;
}

// Whether two particles at squared distance d2 with squared relative displacement a could touch
// within the sub-step: only if |d| <= s + |w|, hence d2 <= (s + |w|)^2 <= 2 (s^2 + a). The line
// test of needs_exact_test ignores time, so in slow scenes it flags many approaching pairs that
// meet only sub-steps later (on the million-particle scene one per particle and sub-step, each
// an exact test with a square root and a division); this bound drops them. Conservative for the
// rounded terms: pair_time's t <= 1 on them implies |d| <= (s + |w|)(1 + ~10 ulp), far inside
// the relative 2^-20 slack. Overlaps (d2 < s2) always pass.  (FLOPS: 2)
template <class T>
inline auto may_touch_within_substep(T d2, T a, double s2) {
  return d2 <= (s2 + a) * (2 * (1 + 0x1p-20));
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
                         may_touch_within_substep(dx * dx + dy * dy, wx * wx + wy * wy, s2))
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

// test_span's spans of more than 8 (sweep's, dense cells'): whole blocks of 64 lanes, then the
// rest as one short span or masked block of 16, 32 or 64 lanes (fixed-length vector loops: no
// scalar remainder, one reduction per block). Out of line, so that the short path inlines into
// the broad phases' loops (the blocks' flag arrays give this one a large stack frame).
[[gnu::noinline]] inline void test_long_span(const RowParticle& p, const SpanArrays& a,
                                             std::uint32_t k0, std::uint32_t k_end, double s2,
                                             ThreadScratch& out) {
  for (; k_end - k0 >= 64; k0 += 64) test_span_block<64, false>(p, a, k0, 64, s2, out);
  const std::uint32_t live = k_end - k0;
  if (live == 0) return;
  if (live <= 8)
    test_short_span(p, a, k0, live, s2, out);
  else if (live <= 16)
    test_span_block<16, true>(p, a, k0, live, s2, out);
  else if (live <= 32)
    test_span_block<32, true>(p, a, k0, live, s2, out);
  else
    test_span_block<64, true>(p, a, k0, live, s2, out);
}

// test_row over a broad phase's copy: particle p against every k in [k_begin, k_end) of `a`.
// The arithmetic is the same functions on the same bits (d = p_k - p), so the candidates, their
// times and the overlap count are exactly those of test_row/test_pair on the World's ids.
// Spans of up to 8 (the cells' at about one particle per cell) take one or two Lanes4; masked
// blocks and groups read up to 63 entries past k_end, hence kSpanPadding (the extra lanes are
// computed and ignored).
inline void test_span(const RowParticle& p, const SpanArrays& a, std::uint32_t k_begin,
                      std::uint32_t k_end, double s2, ThreadScratch& out) {
  if (k_end <= k_begin) return;
  const std::uint32_t live = k_end - k_begin;
  out.pair_tests += live;
  if (live <= 8)
    test_short_span(p, a, k_begin, live, s2, out);
  else
    test_long_span(p, a, k_begin, k_end, s2, out);
}

}  // namespace particle::detail
