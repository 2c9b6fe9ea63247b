#pragma once
// Pair list: the pairs of a CellIndex's half stencils (reach 1) that lay within `bound` on both
// axes when it was built, as pairs of World slots, so that the sub-steps that keep the index
// (broad_phase/cells.hpp) test those pairs alone, on the World's own values, instead of
// refreshing the index and walking the cells again. At
// about one particle per cell a walk finds two or three short spans per particle, a
// data-dependent branch at each cell, span and particle; a flat list of pairs is a loop with no
// branch but the rare flagged pair's, and holds half the pairs the stencil tests (a square of
// half-side one cell around each particle instead of three cells by three).
//
// Built in parallel (static shares of positions, each thread its own list); the set of pairs
// does not depend on the split, and the lists are searched in pieces of kPiece pairs, any thread,
// any order. Memory: 8 bytes a pair.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "broad_phase/cell_index.hpp"
#include "broad_phase/common.hpp"
#include "default_init.hpp"
#include "parallel/team.hpp"
#include "step/float_pretest.hpp"
#include "step/narrow_phase.hpp"
#include "world.hpp"

namespace particle::detail {

class PairList {
  static constexpr std::uint32_t kPiece = 4096;  // pairs a piece of the search

 public:
  // team, barrier at the end: the pairs of `index` (reach 1) with |dx| <= bound and |dy| <= bound
  // at its copy's values.
  void build(const CellIndex& index, double bound) {
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
    team_single([&] {
      by_thread_.resize(threads);
      used_.resize(threads);
    });
    Uninitialized<Pair>& mine = by_thread_[t];  // its size only grows: a place for every pair tried
    std::size_t used = 0;
    const SpanArrays a = index.arrays();
    const std::uint32_t n = index.binned();
    // First build: room for the pairs a square of half-side `bound` holds at this density (a
    // tenth more) rather than growing by doubling, which copies the list and, on the
    // million-particle scene at T = 2, took the peak RSS past 200 MB.
    if (mine.empty()) {
      const double per_particle =
          2 * bound * bound * n /
          (index.cell_side() * index.cell_side() * static_cast<double>(index.cells()));
      mine.resize(static_cast<std::size_t>(1.1 * per_particle * n / threads) + kBuildChunk);
    }
    ahead_ = kAheadRows * (n / static_cast<std::uint32_t>(index.side()));
    const std::uint32_t chunks = (n + kBuildChunk - 1) / kBuildChunk;
#pragma omp for schedule(static) nowait  // shares of n / threads, as the first size assumes
    for (std::uint32_t c = 0; c < chunks; ++c) {
      // Each position's spans from its own cell (CellIndex::near_spans): walking the cells
      // instead (for_half_stencils), the branches on each cell and on the particles in it follow
      // no pattern at about one particle per cell (the build took a tenth longer). The chunk's
      // spans first, then its pairs: in one loop each particle's compares waited on its spans'
      // loads (the million-particle scene's list built alone: 13.0 against 11.8 ms).
      const std::uint32_t first = c * kBuildChunk, stop = std::min(n, first + kBuildChunk);
      CellIndex::NearSpans spans[kBuildChunk];
      std::uint32_t k = first;
#ifdef __AVX2__
      for (; stop - k >= 4; k += 4) index.near_spans4(k, spans + (k - first));
#endif
      for (; k < stop; ++k) spans[k - first] = index.near_spans(k);
      // The list's end and room in locals: the groups' vector stores may alias anything, and
      // through `mine` every one made the loop load its size and data again.
      Pair* out = mine.data() + used;
      Pair* room_end = mine.data() + mine.size();
      for (k = first; k < stop; ++k) {
        const CellIndex::NearSpans s = spans[k - first];
        // Room for both spans and a whole group of eight past each.
        const std::size_t room = (s.own_end - k - 1) + (s.above_end - s.above_begin) + 16;
        if (static_cast<std::size_t>(room_end - out) < room) {
          used = static_cast<std::size_t>(out - mine.data());
          mine.resize(std::max(2 * mine.size(), used + room));
          out = mine.data() + used;
          room_end = mine.data() + mine.size();
        }
        out = keep_near(a, k, s, bound, out);
      }
      used = static_cast<std::size_t>(out - mine.data());
    }
    used_[t] = used;
    team_barrier();  // every list is complete
    team_single([&] {
      // The lists' pieces list by list: the search (team_for) gives each thread a contiguous
      // share of them, so each thread tests mostly its own list's pairs, of the positions its
      // own share of the build and of the advance last touched.
      pieces_.clear();
      for (std::size_t u = 0; u < used_.size(); ++u)
        for (std::size_t first = 0; first < used_[u]; first += kPiece)
          pieces_.push_back({static_cast<std::uint32_t>(u), static_cast<std::uint32_t>(first),
                             static_cast<std::uint32_t>(std::min(used_[u], first + kPiece))});
    });
  }

  std::uint32_t pieces() const { return static_cast<std::uint32_t>(pieces_.size()); }

  // Tests the pairs of piece c, the exact test on the flagged ones alone, unless one of the pair
  // is `apart` (tested apart by the caller). Where `pretest` is given (PARTICLE_FLOAT_PRETEST), on
  // `records`, each World slot's values as floats, kRecordLanes pairs a group (FloatSubStepPretest,
  // 16 with AVX-512, 8 with AVX2); else on the
  // World's own values, eight at a time with AVX-512 (one register; four at a time, the narrow
  // phase took 4 to 8% longer on the million-particle scene), else four, with the short spans'
  // pre-test (test_span_group).
  void test_piece(std::uint32_t c, const World& w, [[maybe_unused]] const FloatParticle* records,
                  [[maybe_unused]] const FloatSubStepPretest* pretest, const std::uint8_t* apart,
                  ThreadScratch& out) const {
    const Piece& piece = pieces_[c];
    const Pair* pairs = by_thread_[piece.list].data();
    Deferred later{w, apart, out};
    const auto flagged_for_later = [&](std::uint32_t q, unsigned flagged) {
      for (; flagged != 0; flagged &= flagged - 1)
        later.add(pairs[q + static_cast<std::uint32_t>(__builtin_ctz(flagged))]);
    };
    // The World's lines (or the records') ahead_ slots on: a pair's partner lies up to about two
    // rows of cells on, and the partners are the first to read each line, in no order a hardware
    // prefetcher follows (the World's order is the cells' at the last re-sort, and the particles
    // have moved since; the later the build, the more the narrow phase waited on them).
    const std::uint32_t last_id = static_cast<std::uint32_t>(w.n) - 1;
#ifdef PARTICLE_FLOAT_PRETEST
    if (pretest) {
      const FloatSubStepPretest t = *pretest;
      std::uint32_t q = piece.first;
      // A group of kRecordLanes pairs, its lanes past `live` the last live pair again where it is
      // partial.
      const auto group = [&](std::uint32_t live, auto full) {
        // About nine particles' pairs in 16 on the million-particle scene: three records' lines.
        const std::uint32_t ahead = pairs[q].i + ahead_;
        for (std::uint32_t a = 0; a <= kRecordLanes / 2; a += 4)
          __builtin_prefetch(records + std::min(ahead + a, last_id));
        const unsigned flagged = flag_records<decltype(full)::value>(t, records, pairs + q, live);
        flagged_for_later(q, full ? flagged : flagged & ((1u << live) - 1));
      };
      for (; piece.last - q >= kRecordLanes; q += kRecordLanes)
        group(kRecordLanes, std::true_type{});
      if (q < piece.last) group(piece.last - q, std::false_type{});
      later.finish();
      out.pair_tests += piece.last - piece.first;
      return;
    }
#endif
#ifdef __AVX512F__
    using Group = Lanes8;
#else
    using Group = Lanes4;
#endif
    constexpr std::uint32_t kLanes = sizeof(Group) / sizeof(double);
    for (std::uint32_t q = piece.first; q < piece.last; q += kLanes) {
      const std::uint32_t live = std::min<std::uint32_t>(kLanes, piece.last - q);
      const std::uint32_t ahead = std::min(pairs[q].i + ahead_, last_id);
      for (const double* a : {w.x, w.y, w.ux, w.uy}) __builtin_prefetch(a + ahead);
      Group dx = {}, dy = {}, wx = {}, wy = {};
      for (std::uint32_t l = 0; l < kLanes; ++l) {
        const Pair pair = pairs[q + std::min(l, live - 1)];  // the last group's dead lanes: again
        dx[l] = w.x[pair.j] - w.x[pair.i];
        dy[l] = w.y[pair.j] - w.y[pair.i];
        wx[l] = w.ux[pair.j] - w.ux[pair.i];
        wy[l] = w.uy[pair.j] - w.uy[pair.i];
      }
      flagged_for_later(q, lane_bits(needs_exact_test(dx, dy, wx, wy, w.s2) &
                                     may_touch_within_substep(dx * dx + dy * dy, dx * wx + dy * wy,
                                                              wx * wx + wy * wy, w.s2)) &
                               ((1u << live) - 1));
    }
    later.finish();
    out.pair_tests += piece.last - piece.first;
  }

 private:
  struct Pair {
    std::uint32_t i, j;  // World slots
  };

#ifdef PARTICLE_FLOAT_PRETEST
  // Each pair's differences {dx, dy, wx, wy} from its records, one 16-byte subtraction; the
  // lanes past `live` (not Full) take the last live pair again.
  template <bool Full, std::size_t N>
  [[gnu::always_inline]] static void differences(const FloatParticle* records, const Pair* pairs,
                                                 std::uint32_t live, __m128 (&d)[N]) {
    for (std::uint32_t l = 0; l < N; ++l) {
      const Pair pair = pairs[Full ? l : std::min(l, live - 1)];
      d[l] = _mm_sub_ps(_mm_loadu_ps(&records[pair.j].x), _mm_loadu_ps(&records[pair.i].x));
    }
  }
#endif

#ifdef __AVX512F__
  static constexpr std::uint32_t kRecordLanes = 16;

  // The float pre-test of pairs[0 .. 15] on their records: their differences transposed (lane
  // 4m + k from pair 4m + k, each 128-bit block a 4 x 4 transpose).
  template <bool Full>
  [[gnu::always_inline]] static unsigned flag_records(const FloatSubStepPretest& t,
                                                      const FloatParticle* records,
                                                      const Pair* pairs, std::uint32_t live) {
    __m128 d[16];
    differences<Full>(records, pairs, live, d);
    __m512 z[4];
    for (int k = 0; k < 4; ++k)
      z[k] = _mm512_insertf32x4(
          _mm512_insertf32x4(_mm512_insertf32x4(_mm512_zextps128_ps512(d[k]), d[k + 4], 1),
                             d[k + 8], 2),
          d[k + 12], 3);
    const __m512d xy01 = _mm512_castps_pd(_mm512_unpacklo_ps(z[0], z[1]));
    const __m512d w01 = _mm512_castps_pd(_mm512_unpackhi_ps(z[0], z[1]));
    const __m512d xy23 = _mm512_castps_pd(_mm512_unpacklo_ps(z[2], z[3]));
    const __m512d w23 = _mm512_castps_pd(_mm512_unpackhi_ps(z[2], z[3]));
    return t.flag16(_mm512_castpd_ps(_mm512_unpacklo_pd(xy01, xy23)),
                    _mm512_castpd_ps(_mm512_unpackhi_pd(xy01, xy23)),
                    _mm512_castpd_ps(_mm512_unpacklo_pd(w01, w23)),
                    _mm512_castpd_ps(_mm512_unpackhi_pd(w01, w23)));
  }
#elif defined(PARTICLE_FLOAT_PRETEST)
  static constexpr std::uint32_t kRecordLanes = 8;

  // The AVX-512 flag_records on eight pairs (AVX2): lane 4m + k from pair 4m + k again, each
  // 128-bit half a 4 x 4 transpose.
  template <bool Full>
  [[gnu::always_inline]] static unsigned flag_records(const FloatSubStepPretest& t,
                                                      const FloatParticle* records,
                                                      const Pair* pairs, std::uint32_t live) {
    __m128 d[8];
    differences<Full>(records, pairs, live, d);
    __m256 z[4];
    for (int k = 0; k < 4; ++k) z[k] = _mm256_set_m128(d[k + 4], d[k]);
    const __m256d xy01 = _mm256_castps_pd(_mm256_unpacklo_ps(z[0], z[1]));
    const __m256d w01 = _mm256_castps_pd(_mm256_unpackhi_ps(z[0], z[1]));
    const __m256d xy23 = _mm256_castps_pd(_mm256_unpacklo_ps(z[2], z[3]));
    const __m256d w23 = _mm256_castps_pd(_mm256_unpackhi_ps(z[2], z[3]));
    return t.flag8(_mm256_castpd_ps(_mm256_unpacklo_pd(xy01, xy23)),
                   _mm256_castpd_ps(_mm256_unpackhi_pd(xy01, xy23)),
                   _mm256_castpd_ps(_mm256_unpacklo_pd(w01, w23)),
                   _mm256_castpd_ps(_mm256_unpackhi_pd(w01, w23)));
  }
#endif

  // The flagged pairs, their exact test kRing flagged pairs later: the float pre-test reads the
  // records alone, so the World's lines of a flagged pair are asked for when it is flagged and
  // read when they have come (on the million-particle scene, a pair in 57, each tested at once
  // waited on memory: the narrow phase 134 -> 166 ms, a third of it in that wait). The double
  // pre-test has read them already.
  class Deferred {
    static constexpr std::uint32_t kRing = 16;

   public:
    Deferred(const World& w, const std::uint8_t* apart, ThreadScratch& out)
        : w_(w), apart_(apart), out_(out) {}

    void add(Pair pair) {
      for (const double* a : {w_.x, w_.y, w_.ux, w_.uy}) {
        __builtin_prefetch(a + pair.i);
        __builtin_prefetch(a + pair.j);
      }
      __builtin_prefetch(apart_ + pair.i);
      __builtin_prefetch(apart_ + pair.j);
      if (added_ >= kRing) test(ring_[added_ % kRing]);
      ring_[added_++ % kRing] = pair;
    }

    void finish() {
      for (std::uint32_t k = added_ > kRing ? added_ - kRing : 0; k < added_; ++k)
        test(ring_[k % kRing]);
    }

   private:
    void test(Pair pair) {
      if (!(apart_[pair.i] | apart_[pair.j])) test_pair(w_, pair.i, pair.j, out_);
    }

    const World& w_;
    const std::uint8_t* apart_;
    ThreadScratch& out_;
    Pair ring_[kRing];
    std::uint32_t added_ = 0;
  };

  static constexpr std::uint32_t kBuildChunk = 1024;  // positions a piece of the build
  // How far ahead of a group's first particle the search asks for the World's lines, in rows of
  // cells. Million-particle scene, cells, T = 1, narrow phase, four runs each: 0 rows 183-188 ms,
  // one row 160-180, two 138-156, three 137-179, four 142-152, six 142-164.
  static constexpr std::uint32_t kAheadRows = 3;

  // Writes {id, a.id[m]} from `out` on for each m in position k's spans (k + 1 to s.own_end, then
  // s.above_begin to s.above_end) with |a.x[m] - x| <= bound and |a.y[m] - y| <= bound, (x, y)
  // and id position k's, in order; returns the end of what it wrote. It may write up to eight
  // pairs past that end, and reads up to seven positions past a span's end (the index's padding).
  // With AVX-512, where both spans fit in eight lanes (nearly always at one particle a cell: about
  // one or two positions in the own row, three in the row above), the row above's positions are
  // expanded into the lanes after the own row's and the eight compared at once (one group, not
  // two: the million-particle scene's list built alone, 11.8 against 9.4 ms).
  static Pair* keep_near(const SpanArrays& a, std::uint32_t k, const CellIndex::NearSpans& s,
                         double bound, Pair* out) {
    const std::uint32_t id = a.id[k];
    const double x = a.x[k], y = a.y[k];
#ifdef __AVX512F__
    const std::uint32_t own = s.own_end - (k + 1), above = s.above_end - s.above_begin;
    if (own + above <= 8) {
      const auto after = static_cast<__mmask8>(0xFFu << own);
      const __m512d px = _mm512_mask_expand_pd(_mm512_loadu_pd(a.x + k + 1), after,
                                               _mm512_loadu_pd(a.x + s.above_begin));
      const __m512d py = _mm512_mask_expand_pd(_mm512_loadu_pd(a.y + k + 1), after,
                                               _mm512_loadu_pd(a.y + s.above_begin));
      const __m512i j = _mm512_mask_expand_epi64(ids(a, k + 1), after, ids(a, s.above_begin));
      return keep_lanes(px, py, j, static_cast<__mmask8>((1u << (own + above)) - 1), id, x, y,
                        bound, out);
    }
#elif defined(__AVX2__)
    // With AVX2, where the own row's positions fit in four lanes and the row above's in eight
    // (nearly always at one particle a cell), a group each and a third only where the row above
    // holds more than four: a loop per span exits after a count that follows no pattern, but the
    // third group's branch (taken by about one particle in five) cost less than the group (the
    // slow crowd's list 8% faster).
    const std::uint32_t own = s.own_end - (k + 1), above = s.above_end - s.above_begin;
    if (own <= 4 && above <= 8) {
      const auto lanes = [](std::uint32_t count) { return (1u << std::min(count, 4u)) - 1; };
      out = keep_lanes(a, k + 1, lanes(own), id, x, y, bound, out);
      out = keep_lanes(a, s.above_begin, lanes(above), id, x, y, bound, out);
      if (above <= 4) return out;
      return keep_lanes(a, s.above_begin + 4, lanes(above - 4), id, x, y, bound, out);
    }
#endif
    out = keep_span(a, id, x, y, bound, k + 1, s.own_end, out);
    return keep_span(a, id, x, y, bound, s.above_begin, s.above_end, out);
  }

  // keep_near() for one span, [begin, end). About half the positions are kept, in no pattern a
  // branch predictor could learn: the scalar loop writes every pair and advances only for a kept
  // one; with AVX-512, a span is compared eight positions at a time and compressed in a register
  // (a compressing store to memory is microcoded on AMD's Zen 4).
  static Pair* keep_span(const SpanArrays& a, std::uint32_t id, double x, double y, double bound,
                         std::uint32_t begin, std::uint32_t end, Pair* out) {
#ifdef __AVX512F__
    std::uint32_t m = begin;
    do {  // an empty span too: a group with no live lane, rather than a branch around it
      const std::uint32_t left = end > m ? end - m : 0;
      const auto live = static_cast<__mmask8>(left >= 8 ? 0xFF : (1u << left) - 1);
      out = keep_lanes(_mm512_loadu_pd(a.x + m), _mm512_loadu_pd(a.y + m), ids(a, m), live, id, x,
                       y, bound, out);
      m += 8;
    } while (m < end);
#elif defined(__AVX2__)
    std::uint32_t m = begin;
    do {
      const std::uint32_t left = end > m ? end - m : 0;
      out = keep_lanes(a, m, left >= 4 ? 0xFu : (1u << left) - 1, id, x, y, bound, out);
      m += 4;
    } while (m < end);
#else
    for (std::uint32_t m = begin; m < end; ++m) {
      *out = {id, a.id[m]};
      out += (std::fabs(a.x[m] - x) <= bound) & (std::fabs(a.y[m] - y) <= bound);
    }
#endif
    return out;
  }

#ifdef __AVX512F__
  // The ids of positions m to m + 7, widened to Pair's j (the high half, once shifted).
  static __m512i ids(const SpanArrays& a, std::uint32_t m) {
    return _mm512_cvtepu32_epi64(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(a.id + m)));
  }

  // One group: writes {id, j} from `out` on for each `live` lane whose (px, py) lies within bound
  // of (x, y) on both axes, in lane order (eight pairs written); returns the end of the kept ones.
  static Pair* keep_lanes(__m512d px, __m512d py, __m512i j, __mmask8 live, std::uint32_t id,
                          double x, double y, double bound, Pair* out) {
    const __m512d vb = _mm512_set1_pd(bound);
    const __mmask8 near = _mm512_mask_cmp_pd_mask(
        _mm512_mask_cmp_pd_mask(live, _mm512_abs_pd(_mm512_sub_pd(px, _mm512_set1_pd(x))), vb,
                                _CMP_LE_OQ),
        _mm512_abs_pd(_mm512_sub_pd(py, _mm512_set1_pd(y))), vb, _CMP_LE_OQ);
    const __m512i vi = _mm512_set1_epi64(id);  // Pair's i, the low half (little-endian)
    _mm512_storeu_si512(
        out, _mm512_maskz_compress_epi64(near, _mm512_or_si512(vi, _mm512_slli_epi64(j, 32))));
    return out + __builtin_popcount(near);
  }
#elif defined(__AVX2__)
  // For each set of up to four lanes (a mask), the 32-bit elements of their pairs in order, for
  // a compressing permutation (AVX2 has no compress).
  static constexpr auto kCompress = [] {
    std::array<std::array<std::int32_t, 8>, 16> table{};
    for (unsigned mask = 0; mask < 16; ++mask) {
      int kept = 0;
      for (int lane = 0; lane < 4; ++lane)
        if (mask >> lane & 1) {
          table[mask][2 * kept] = 2 * lane;
          table[mask][2 * kept + 1] = 2 * lane + 1;
          ++kept;
        }
    }
    return table;
  }();

  // One group of four, positions m to m + 3 of `a`, `live` a mask of them: writes {id, a.id[m']}
  // from `out` on for each live position m' within bound of (x, y) on both axes, in order (four
  // pairs written); returns the end of the kept ones.
  static Pair* keep_lanes(const SpanArrays& a, std::uint32_t m, unsigned live, std::uint32_t id,
                          double x, double y, double bound, Pair* out) {
    const __m256d vb = _mm256_set1_pd(bound), sign = _mm256_set1_pd(-0.0);
    const __m256d dx =
        _mm256_andnot_pd(sign, _mm256_sub_pd(_mm256_loadu_pd(a.x + m), _mm256_set1_pd(x)));
    const __m256d dy =
        _mm256_andnot_pd(sign, _mm256_sub_pd(_mm256_loadu_pd(a.y + m), _mm256_set1_pd(y)));
    const unsigned near =
        static_cast<unsigned>(_mm256_movemask_pd(
            _mm256_and_pd(_mm256_cmp_pd(dx, vb, _CMP_LE_OQ), _mm256_cmp_pd(dy, vb, _CMP_LE_OQ)))) &
        live;
    const __m256i j =
        _mm256_cvtepu32_epi64(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a.id + m)));
    const __m256i pairs = _mm256_or_si256(_mm256_set1_epi64x(id), _mm256_slli_epi64(j, 32));
    _mm256_storeu_si256(
        reinterpret_cast<__m256i*>(out),
        _mm256_permutevar8x32_epi32(
            pairs, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kCompress[near].data()))));
    return out + __builtin_popcount(near);
  }
#endif

  struct Piece {
    std::uint32_t list, first, last;  // pairs [first, last) of by_thread_[list]
  };

  std::vector<Uninitialized<Pair>> by_thread_;  // written before read: resize() need not zero
  std::vector<std::size_t> used_;               // the pairs of each thread's list
  std::vector<Piece> pieces_;
  std::uint32_t ahead_ = 0;  // slots: kAheadRows rows of the last build's cells
};

}  // namespace particle::detail
