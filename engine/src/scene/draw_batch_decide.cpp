// A sorted batch's decisions (scene/draw_batch.hpp): draw p is refused where an earlier entry
// closer than s is accepted, accepted where all such are refused (or there are none), the
// sequential rule's decision whatever the order they are taken in, since decisions are final.
//
// Rows in cell order, a band of rows a thread. A row's draws first get their first two earlier
// entries closer than s (find_earlier), then each is judged from their decisions as they stand:
// about 84% are decided at once at the million scene; the rest wait on an earlier draw ahead in
// the sweep and are judged again after the next row, while their cells are in cache (all but 1%),
// then in sweeps over what is left until none is (each decides at least the earliest undecided
// draw). A decision is an atomic byte, read and written by the threads of neighbouring bands
// alike: the same decisions on any number of threads.
#include <algorithm>
#include <bit>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

#include "scene/draw_batch.hpp"
#include "scene/pieces.hpp"

namespace particle::detail {

// A draw left undecided by a sweep, and its first two earlier entries closer than s.
struct DrawBatch::Undecided {
  std::uint32_t p, a, b;
};

namespace {

// The first entry of [from, end) whose column is at least `column`, in a row sorted by column:
// with AVX-512, 32 columns a step.
std::uint32_t first_column(const std::uint16_t* columns, std::uint32_t from, std::uint32_t end,
                           std::uint32_t column) {
#if defined(__AVX512BW__) && defined(__AVX512VL__)
  for (; from < end; from += 32) {
    const auto in = static_cast<__mmask32>(_bzhi_u32(~0u, std::min(end - from, 32u)));
    const __mmask32 past =
        _mm512_mask_cmpge_epu16_mask(in, _mm512_maskz_loadu_epi16(in, &columns[from]),
                                     _mm512_set1_epi16(static_cast<short>(column)));
    if (past != 0) return from + static_cast<std::uint32_t>(std::countr_zero(past));
  }
  return end;
#else
  while (from < end && columns[from] < column) ++from;
  return from;
#endif
}

}  // namespace

// Row cy's first entry in cell `column` or past it: from the signpost before it, a few entries on.
std::uint32_t DrawBatch::first_in(std::size_t cy, std::uint32_t column) const {
  return first_column(column_.data(), signposts_[cy * signposts_a_row() + column / kSignpost],
                      row_starts_[cy + 1], column);
}

// The first two earlier entries closer than s of row cy's draws, a pair a draw into row_earlier
// (none() or more() past those found), from their 3 x 3 cells. With AVX-512, eight draws at a time
// against each entry of the cells around any of them, an entry's own cells told by its column: no
// branch on what the entries are (a draw's neighbours are as often earlier as later, as often
// closer than s as not, and such branches mispredict half the time), and all eight lanes at work
// where a row's three cells around one draw hold 1.3 entries at the million scene.
void DrawBatch::find_earlier(std::size_t cy, std::uint32_t* row_earlier) const {
  const std::size_t g = g_;
  const std::uint32_t* order = order_.data();
  const std::uint16_t* column = column_.data();
  const double *x = x_.data(), *y = y_.data();
  std::uint32_t* earlier = row_earlier - 2 * std::size_t{row_starts_[cy]};
  const std::size_t y_from = cy > 0 ? cy - 1 : 0, y_to = std::min(g - 1, cy + 1) + 1;
  const std::uint32_t row_end = row_starts_[cy + 1];
  std::uint32_t from[3], to[3];  // the three rows' entries in columns [x_from, x_to)
#if defined(__AVX512BW__) && defined(__AVX512VL__)
  const auto cells_around = [&](std::uint32_t x_from, std::uint32_t x_to) {
    for (std::size_t gy = y_from; gy < y_to; ++gy) {
      from[gy - y_from] = first_in(gy, x_from);
      to[gy - y_from] = first_in(gy, x_to);
    }
  };
  const __m256i one = _mm256_set1_epi32(1), two = _mm256_set1_epi32(2);
  const __m256i nothing = _mm256_set1_epi32(static_cast<int>(none()));
  for (std::uint32_t p = row_starts_[cy]; p < row_end; p += 8) {
    const std::uint32_t n = std::min(8u, row_end - p);
    const auto lanes = static_cast<__mmask8>(_bzhi_u32(0xff, n));
    const __m512d px = _mm512_maskz_loadu_pd(lanes, &x[p]),
                  py = _mm512_maskz_loadu_pd(lanes, &y[p]);
    const __m256i po = _mm256_maskz_loadu_epi32(lanes, &order[p]);
    const __m256i pcx = _mm256_cvtepu16_epi32(_mm_maskz_loadu_epi16(lanes, &column[p]));
    cells_around(column[p] > 0 ? column[p] - 1u : 0, column[p + n - 1] + 2u);
    __m256i first = nothing, second = nothing, found = _mm256_setzero_si256();
    for (std::size_t k = 0; k < y_to - y_from; ++k)
      for (std::uint32_t q = from[k]; q < to[k]; ++q) {
        // earlier, in a cell next to the draw's (column[q] - column + 1 in [0, 2]), closer than s
        __mmask8 near =
            _mm256_mask_cmplt_epu32_mask(lanes, _mm256_set1_epi32(static_cast<int>(order[q])), po);
        near = _mm256_mask_cmple_epu32_mask(
            near, _mm256_add_epi32(_mm256_sub_epi32(_mm256_set1_epi32(column[q]), pcx), one), two);
        near = cells_.closer(near, _mm512_set1_pd(x[q]), _mm512_set1_pd(y[q]), px, py);
        const __m256i at = _mm256_set1_epi32(static_cast<int>(q));
        first = _mm256_mask_mov_epi32(
            first, _mm256_mask_cmpeq_epi32_mask(near, found, _mm256_setzero_si256()), at);
        second = _mm256_mask_mov_epi32(second, _mm256_mask_cmpeq_epi32_mask(near, found, one), at);
        found = _mm256_mask_add_epi32(found, near, found, one);
      }
    second = _mm256_mask_mov_epi32(second, _mm256_cmpgt_epu32_mask(found, two),
                                   _mm256_set1_epi32(static_cast<int>(more())));
    // a0 b0 a1 b1 ... in draw order: interleaved within the 128-bit halves, then the halves
    const __m256i low = _mm256_unpacklo_epi32(first, second),
                  high = _mm256_unpackhi_epi32(first, second);
    _mm256_mask_storeu_epi32(&earlier[2 * p], static_cast<__mmask8>(_bzhi_u32(0xff, 2 * n)),
                             _mm256_permute2x128_si256(low, high, 0x20));
    if (n > 4)
      _mm256_mask_storeu_epi32(&earlier[2 * p + 8],
                               static_cast<__mmask8>(_bzhi_u32(0xff, 2 * n - 8)),
                               _mm256_permute2x128_si256(low, high, 0x31));
  }
#else
  // Without AVX-512 each range moves on from the last draw's (the columns grow along the row):
  // about 60 instructions a draw fewer than the signposts' searches at make regress's crowd.
  std::uint32_t end[3];
  for (std::size_t gy = y_from; gy < y_to; ++gy) {
    from[gy - y_from] = to[gy - y_from] = row_starts_[gy];
    end[gy - y_from] = row_starts_[gy + 1];
  }
  for (std::uint32_t p = row_starts_[cy]; p < row_end; ++p) {
    const std::uint32_t x_from = column[p] > 0 ? column[p] - 1u : 0, x_to = column[p] + 2u;
    for (std::size_t k = 0; k < y_to - y_from; ++k) {
      while (from[k] < end[k] && column[from[k]] < x_from) ++from[k];
      to[k] = std::max(to[k], from[k]);
      while (to[k] < end[k] && column[to[k]] < x_to) ++to[k];
    }
    std::uint32_t found[3], count = 0;  // the first two, then what is written past them
    for (std::size_t k = 0; k < y_to - y_from; ++k)
      for (std::uint32_t q = from[k]; q < to[k]; ++q) {
        found[std::min(count, 2u)] = q;
        count += (order[q] < order[p]) & cells_.closer(x[q], y[q], x[p], y[p]);
      }
    earlier[2 * p] = count > 0 ? found[0] : none();
    earlier[2 * p + 1] = count > 2 ? more() : count > 1 ? found[1] : none();
  }
#endif
}

// A draw's decision as its earlier entries closer than s stand (a, b: the first two, or none() or
// more() past them). A table, not branches: a decision goes either way as often as not.
std::uint8_t DrawBatch::judge(std::uint32_t a, std::uint32_t b) const {
  constexpr unsigned kByFound =  // by bits 1 << decision of a and of b
      kUndecided << 4 | kRefused << 8 | kRefused << 12 | kAccepted << 16 | kUndecided << 20 |
      kRefused << 24 | kRefused << 28;
  const unsigned found = 1u << decision(a) | 1u << decision(b);
  return static_cast<std::uint8_t>(kByFound >> (4 * found) & 0xf);
}

// judge() for draw p with more than two earlier entries closer than s: all of them, from its
// 3 x 3 cells.
std::uint8_t DrawBatch::judge_by_cells(std::size_t p) const {
  const std::size_t cx = column_[p], cy = static_cast<std::size_t>(cells_.cell_of(y_[p]));
  bool waits = false;
  for (std::size_t gy = cy > 0 ? cy - 1 : 0; gy <= std::min(g_ - 1, cy + 1); ++gy) {
    const std::uint32_t to = first_in(gy, static_cast<std::uint32_t>(cx + 2));
    for (std::uint32_t q = first_in(gy, static_cast<std::uint32_t>(cx > 0 ? cx - 1 : 0)); q < to;
         ++q) {
      if (order_[q] >= order_[p] || !cells_.closer(x_[q], y_[q], x_[p], y_[p])) continue;
      const std::uint8_t d = decision(q);
      if (d == kAccepted) return kRefused;
      waits |= d == kUndecided;
    }
  }
  return waits ? kUndecided : kAccepted;
}

// Judges the draws of `undecided` again, as things now stand, each decision also to its draw's
// place in `by_order`; keeps those still undecided.
void DrawBatch::judge_again(std::vector<Undecided>& undecided, std::uint8_t* by_order) {
  std::size_t kept = 0;
  for (const Undecided& u : undecided) {
    const std::uint8_t d = u.b == more() ? judge_by_cells(u.p) : judge(u.a, u.b);
    decide(u.p, d);
    std::atomic_ref<std::uint8_t>(by_order[order_[u.p]]).store(d, std::memory_order_relaxed);
    undecided[kept] = u;
    kept += d == kUndecided;
  }
  undecided.resize(kept);
}

// Rows [row_from, row_to) in cell order; the draws still undecided after the next row into `left`.
// by_order[order] of the kept disks (0) is written by every band: atomic bytes.
void DrawBatch::sweep(std::size_t row_from, std::size_t row_to, std::uint8_t* by_order,
                      std::vector<Undecided>& left) {
  std::vector<std::uint32_t> earlier;
  std::vector<Undecided> last_row, row;
  const std::uint32_t* order = order_.data();
  for (std::size_t cy = row_from; cy < row_to; ++cy) {
    const std::uint32_t from = row_starts_[cy], to = row_starts_[cy + 1];
    earlier.resize(2 * std::size_t{to - from});
    find_earlier(cy, earlier.data());
    row.resize(to - from);
    const std::uint32_t* found = earlier.data();
    Undecided* waiting = row.data();
    std::size_t undecided = 0;
    for (std::uint32_t p = from; p < to; ++p, found += 2) {
      const std::uint8_t d = judge(found[0], found[1]);
      decide(p, d);
      std::atomic_ref<std::uint8_t>(by_order[order[p]]).store(d, std::memory_order_relaxed);
      waiting[undecided] = {p, found[0], found[1]};
      undecided += d == kUndecided;
    }
    row.resize(undecided);
    judge_again(last_row, by_order);
    left.insert(left.end(), last_row.begin(), last_row.end());
    std::swap(last_row, row);
  }
  judge_again(last_row, by_order);
  left.insert(left.end(), last_row.begin(), last_row.end());
}

void DrawBatch::decide(int threads, std::uint8_t* by_order) {
  const std::size_t bands = std::min(static_cast<std::size_t>(threads), g_);
  std::vector<std::vector<Undecided>> left(bands);
  for_pieces(threads, bands, [&](std::size_t band) {
    sweep(band * g_ / bands, (band + 1) * g_ / bands, by_order, left[band]);
  });
  const auto undecided = [&] {
    return std::any_of(left.begin(), left.end(), [](const auto& l) { return !l.empty(); });
  };
  while (undecided())
    for_pieces(threads, bands, [&](std::size_t band) { judge_again(left[band], by_order); });
}

}  // namespace particle::detail
