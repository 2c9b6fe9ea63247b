#pragma once
// Cell index: particles counting-sorted into an n x n grid of square cells over [0, L]^2, in
// row-major cell order, with a contiguous copy of their values (CSR layout). The cells of one row
// are adjacent in memory, so "cells cx-k..cx+k of row cy" is one contiguous span that the narrow
// phase tests with one vectorized loop. Shared by the grid and cells broad phases.
//
// Build, O(N + cells) per sub-step, parallel and deterministic: each thread bins its share of
// slots (a contiguous range) and counts them into its own histogram, the histograms are
// prefix-summed over (cell, thread), and each thread scatters its share again, straight into the
// SoA copy. Within a cell particles stay in slot order for every thread count (the static shares
// are slot ranges in thread order). The cells engine keeps the World in cell order
// (broad_phase/cell_order.hpp), so the scatter's writes are nearly sequential; from a random order
// they were the build's main cost (a packed record per particle and a pass to the SoA were then
// faster). Memory: 40 bytes per particle (24 without the velocities, copy_velocities()) plus 4
// bytes per cell per thread.
//
// Pair enumeration (half stencil with a reach of k cells): particle at position p of cell (cx, cy)
// is tested against [p+1, end of cell cx+k) in its own row and against cells cx-k..cx+k of rows
// cy+1..cy+k. Every pair of binned particles whose cells differ by at most k on both axes is
// tested exactly once: from the earlier one in CSR order in a shared row, else from the lower row.
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "broad_phase/common.hpp"
#include "default_init.hpp"
#include "parallel/team.hpp"
#include "step/narrow_phase.hpp"
#include "world.hpp"

namespace particle::detail {

class CellIndex {
  static constexpr std::size_t kAhead = 16;  // prefetch distance of the scatter, in particles

 public:
  static constexpr std::uint32_t kNotBinned = 0xFFFFFFFFu;

  // single thread (or every thread with the same values): an n x n grid of cells of side L / n.
  void set_grid(int n, double L) {
    n_ = std::max(1, n);
    inverse_cell_ = n_ / L;
    cell_side_ = L / n_;
  }
  double cell_side() const { return cell_side_; }
  int side() const { return n_; }  // cells

  // single thread, before build(): whether the copy holds the velocities too. A pair list built
  // from the positions (broad_phase/pair_list.hpp) needs none: without them a build writes 20
  // bytes a particle instead of 36, and the million-particle scene holds 16 MB less.
  void copy_velocities(bool copy) { velocities_ = copy; }
  std::uint32_t cells() const { return static_cast<std::uint32_t>(n_) * n_; }

  // The cell column (or row) of coordinate x in [0, L] (cell_column).
  int column(double x) const {
    return static_cast<int>(cell_column(x, inverse_cell_, static_cast<std::uint32_t>(n_)));
  }
  std::uint32_t cell_of(double x, double y) const {
    return static_cast<std::uint32_t>(column(y)) * n_ + column(x);
  }
#ifdef __AVX2__
  // cell_of() of four particles.
  __m128i cells_of(__m256d x, __m256d y) const {
    return _mm_add_epi32(_mm_mullo_epi32(columns(y), _mm_set1_epi32(n_)), columns(x));
  }
  // column() of four coordinates: cell_column()'s clamps, in double, then the truncation.
  __m128i columns(__m256d v) const {
    return _mm256_cvttpd_epi32(_mm256_min_pd(
        _mm256_max_pd(_mm256_mul_pd(v, _mm256_set1_pd(inverse_cell_)), _mm256_setzero_pd()),
        _mm256_set1_pd(n_ - 1)));
  }
#endif

  // team, barrier at the end. bin(lo, hi, cells) is called once on each thread's static share
  // [lo, hi) of the particles and writes each one's cell to cells[i], or kNotBinned to leave it
  // out of the index (a range, so that it can bin several particles a register). before() runs on
  // one thread before anything else (it may call set_grid), flush() on every thread after its
  // bin() call, after() on one thread at the end; they ride on barriers the build needs anyway.
  template <class Before, class Bin, class Flush, class After>
  void build(const World& w, Before&& before, Bin&& bin, Flush&& flush, After&& after) {
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
    team_single([&] {
      before();
      fit(w.n, threads);
    });
    const std::uint32_t cells = this->cells();
    const bool velocities = velocities_;
    std::uint32_t* hist = histogram_.data() + static_cast<std::size_t>(t) * cells;
    // Same static share as the scatter below: chunk [lo, hi) of the ids.
    const std::size_t lo = w.n * t / threads, hi = w.n * (t + 1) / threads;
    bin(lo, hi, cell_of_.data());
    std::uint32_t first_cell = cells, last_cell = 0;
    for (std::size_t i = lo; i < hi; ++i) {  // kNotBinned is above every cell, and + 1 wraps to 0
      first_cell = std::min(first_cell, cell_of_[i]);
      last_cell = std::max(last_cell, cell_of_[i] + 1);
    }
    flush();
    // A thread's histogram is only its particles' cells, [first_cell, last_cell): in cell order
    // (the cells engine keeps the World so) each thread's share of the slots fills its own part of
    // the grid, and with one particle a cell, zeroing and prefix-summing every cell of every
    // thread's histogram was as much work as the particles', the more the threads.
    range_[t] = {std::min(first_cell, last_cell), last_cell};
    std::fill(hist + range_[t].first, hist + range_[t].second, 0u);
    for (std::size_t i = lo; i < hi; ++i) {  // counting apart, so the cursor can be prefetched
      if (i + kAhead < hi) {
        const std::uint32_t ahead = cell_of_[i + kAhead];
        if (ahead != kNotBinned) __builtin_prefetch(&hist[ahead], 1);
      }
      const std::uint32_t c = cell_of_[i];
      if (c != kNotBinned) ++hist[c];
    }
    team_barrier();
    prefix_sum(t, threads);
    team_barrier();
    for (std::size_t i = lo; i < hi; ++i) {
      // Fetch the cursor of a particle a little ahead (a hint, so any value is safe): in a
      // random order it is a random access.
      if (i + kAhead < hi) {
        const std::uint32_t ahead = cell_of_[i + kAhead];
        if (ahead != kNotBinned) __builtin_prefetch(&hist[ahead], 1);
      }
      const std::uint32_t c = cell_of_[i];
      if (c == kNotBinned) continue;
      const std::uint32_t k = hist[c]++;
      x_[k] = w.x[i];
      y_[k] = w.y[i];
      if (velocities) {
        ux_[k] = w.ux[i];
        uy_[k] = w.uy[i];
      }
      id_[k] = static_cast<std::uint32_t>(i);
    }
    // after() reads only what the barriers above completed; the single's closing barrier is the
    // one that completes the scatter.
    team_single([&] {
      binned_ = end_[cells - 1];
      pad_copy();
      after();
    });
  }

  // Any thread, on a copy with the velocities: copies the current values of the particles at
  // positions [k_first, k_last) from the World into the copy, each where the last build() put it,
  // and calls visit(k) on each. The cells stay those of the build (the cells engine keeps them
  // while it can prove that no pair it leaves out can collide, broad_phase/cells.hpp); the span
  // tests then see this sub-step's values.
  // A gather by id, nearly sequential when the World is in cell order. Where visit(k) returns
  // false, x becomes a NaN: every comparison of the pre-tests is false on it, so no span or box
  // test flags the particle (its caller tests it apart).
  template <class Visit>
  void refresh(const World& w, std::uint32_t k_first, std::uint32_t k_last, Visit&& visit) {
    for (std::uint32_t k = k_first; k < k_last; ++k) {
      const std::uint32_t i = id_[k];
      x_[k] = w.x[i];
      y_[k] = w.y[i];
      ux_[k] = w.ux[i];
      uy_[k] = w.uy[i];
      if (!visit(k)) x_[k] = std::numeric_limits<double>::quiet_NaN();
    }
  }

  std::uint32_t binned() const { return binned_; }
  std::uint32_t begin(std::uint32_t c) const { return c ? end_[c - 1] : 0; }
  std::uint32_t end(std::uint32_t c) const { return end_[c]; }
  RowParticle particle(std::uint32_t k) const { return {x_[k], y_[k], ux_[k], uy_[k], id_[k]}; }
  SpanArrays arrays() const { return {x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()}; }

  // Tests the particles at positions [k_first, k_last) against their half stencils of reach
  // `reach` cells.
  void test_half_stencils(std::uint32_t k_first, std::uint32_t k_last, int reach, double s2,
                          ThreadScratch& out) const {
    const SpanArrays a = arrays();
    for_half_stencils(k_first, k_last, reach, [&](std::uint32_t k) {
      return [&, p = particle(k)](std::uint32_t span_begin, std::uint32_t span_end) {
        test_span(p, a, span_begin, span_end, s2, out);
      };
    });
  }

  // For each position k in [k_first, k_last), visit(k) once, then the span visitor it returns on
  // every span [begin, end) of k's half stencil of reach `reach` cells: positions k + 1 to the end
  // of cell cx + reach in its own row, then cells cx - reach .. cx + reach of each row above it,
  // up to `reach` rows (a span may be empty). What k's spans share (its values) is loaded once per
  // k, not per span (per span, it cost grid 2.6% more instructions). Walks the cells as it goes,
  // so the spans are found once per cell rather than once per particle (at about one particle per
  // cell, finding them was a third of the narrow phase).
  template <class Visit>
  void for_half_stencils(std::uint32_t k_first, std::uint32_t k_last, int reach,
                         Visit&& visit) const {
    if (k_first >= k_last) return;
    // The cell holding k_first: the first whose end lies past it.
    auto c = static_cast<std::uint32_t>(std::upper_bound(end_.begin(), end_.end(), k_first) -
                                        end_.begin());
    int cx = static_cast<int>(c % static_cast<std::uint32_t>(n_));
    int cy = static_cast<int>(c / static_cast<std::uint32_t>(n_));
    for (std::uint32_t k = k_first; k < k_last; ++c) {
      if (end_[c] > k) {  // a cell with particles in range
        const int lo = std::max(0, cx - reach), hi = std::min(n_ - 1, cx + reach);
        const int top = std::min(n_ - 1, cy + reach);
        const std::uint32_t row = static_cast<std::uint32_t>(cy) * n_;
        const std::uint32_t own_end = end_[row + hi];
        for (const std::uint32_t stop = std::min(end_[c], k_last); k < stop; ++k) {
          auto span = visit(k);
          span(k + 1, own_end);
          for (int ry = cy + 1; ry <= top; ++ry) {
            const std::uint32_t r = static_cast<std::uint32_t>(ry) * n_;
            span(begin(r + lo), end_[r + hi]);
          }
        }
      }
      if (++cx == n_) {
        cx = 0;
        ++cy;
      }
    }
  }

  // The spans of position k's half stencil of reach one (for_half_stencils()), its cell found from
  // its coordinates, which holds while the copy is as build() left it (refresh() may put a NaN in
  // x): positions k + 1 to own_end, and above_begin to above_end (empty in the top row).
  struct NearSpans {
    std::uint32_t own_end, above_begin, above_end;
  };
  NearSpans near_spans(std::uint32_t k) const { return near_spans(column(x_[k]), column(y_[k])); }
#ifdef __AVX2__
  // near_spans() of positions k to k + 3.
  void near_spans4(std::uint32_t k, NearSpans* spans) const {
    alignas(16) std::int32_t cx[4], cy[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(cx), columns(_mm256_loadu_pd(x_.data() + k)));
    _mm_store_si128(reinterpret_cast<__m128i*>(cy), columns(_mm256_loadu_pd(y_.data() + k)));
    for (int l = 0; l < 4; ++l) spans[l] = near_spans(cx[l], cy[l]);
  }
#endif
  NearSpans near_spans(int cx, int cy) const {
    const std::uint32_t row = static_cast<std::uint32_t>(cy) * n_;
    const auto lo = static_cast<std::uint32_t>(std::max(0, cx - 1));
    const auto hi = static_cast<std::uint32_t>(std::min(n_ - 1, cx + 1));
    const bool above = cy + 1 < n_;  // selects, not a branch: the top row is rare
    return {end_[row + hi], above ? begin(row + n_ + lo) : 0, above ? end_[row + n_ + hi] : 0};
  }

  // Tests an outside particle (not binned) against every binned particle in the cells that
  // [x - reach_x, x + reach_x] x [y - reach_y, y + reach_y] touches.
  void test_box(const RowParticle& p, double reach_x, double reach_y, double s2,
                ThreadScratch& out) const {
    const SpanArrays a = arrays();
    for_box(p.x, p.y, reach_x, reach_y, [&](std::uint32_t span_begin, std::uint32_t span_end) {
      test_span(p, a, span_begin, span_end, s2, out);
    });
  }

  // visit(begin, end) for the span of positions of each row of the cells that
  // [x - reach_x, x + reach_x] x [y - reach_y, y + reach_y] touches.
  template <class Visit>
  void for_box(double x, double y, double reach_x, double reach_y, Visit&& visit) const {
    const int lo = column(x - reach_x), hi = column(x + reach_x);
    const int bottom = column(y - reach_y), top = column(y + reach_y);
    for (int ry = bottom; ry <= top; ++ry) {
      const std::uint32_t r = static_cast<std::uint32_t>(ry) * n_;
      visit(begin(r + lo), end_[r + hi]);
    }
  }

  // visit(begin, end) for the spans of positions of row `row`'s cells on the grid's border: the
  // whole row in the first and last rows, else its first and last cells.
  template <class Visit>
  void for_border_of_row(int row, Visit&& visit) const {
    const std::uint32_t r = static_cast<std::uint32_t>(row) * n_;
    if (row == 0 || row == n_ - 1) {
      visit(begin(r), end_[r + n_ - 1]);
    } else {
      visit(begin(r), end_[r]);
      visit(begin(r + n_ - 1), end_[r + n_ - 1]);
    }
  }

  // The particle (World id) at position k.
  std::uint32_t id(std::uint32_t k) const { return id_[k]; }

  // Any thread: once the World's particles at positions [k_first, k_last) were moved to the slots
  // of those positions (broad_phase/cells.hpp, resort()), the positions name them there.
  void renumber(std::uint32_t k_first, std::uint32_t k_last) {
    for (std::uint32_t k = k_first; k < k_last; ++k) id_[k] = k;
  }

 private:
  // single thread: the arrays for n particles, `threads` histograms of this grid's cells.
  void fit(std::size_t n, int threads) {
    const std::uint32_t cells = this->cells();
    histogram_.resize(static_cast<std::size_t>(threads) * cells);
    end_.resize(cells);
    cell_of_.resize(n);
    chunk_total_.assign(threads, 0);
    range_.resize(threads);
    const std::size_t padded_size = n + kSpanPadding;  // every particle, binned or not
    if (x_.size() < padded_size) {
      x_.resize(padded_size);
      y_.resize(padded_size);
      id_.resize(padded_size);
    }
    if (velocities_ && ux_.size() < padded_size) {
      ux_.resize(padded_size);
      uy_.resize(padded_size);
    }
  }

  // team, one barrier inside: the histograms' counts become each (cell, thread)'s first position,
  // prefix-summed over (cell, thread), and end_ each cell's end. Thread t owns cells [c0, c1).
  // A cell outside a thread's range_ counts none of its particles: the cells are taken in
  // stretches over which the same threads' ranges hold them, so a stretch that one thread alone
  // holds (nearly all, in cell order) is a loop over one histogram.
  void prefix_sum(int t, int threads) {
    const std::uint32_t cells = this->cells();
    const std::uint32_t c0 = static_cast<std::uint32_t>(std::uint64_t(cells) * t / threads);
    const std::uint32_t c1 = static_cast<std::uint32_t>(std::uint64_t(cells) * (t + 1) / threads);
    const auto hist = [&](int u) { return histogram_.data() + std::size_t(u) * cells; };
    std::uint32_t total = 0;
    for (int u = 0; u < threads; ++u) {
      const std::uint32_t* h = hist(u);
      for (std::uint32_t c = std::max(c0, range_[u].first), e = std::min(c1, range_[u].second);
           c < e; ++c)
        total += h[c];
    }
    chunk_total_[t] = total;
    team_barrier();
    std::uint32_t run = 0;
    for (int u = 0; u < t; ++u) run += chunk_total_[u];
    std::vector<int> holders;
    for (std::uint32_t c = c0; c < c1;) {
      // The stretch from c: up to the next start or end of a range.
      std::uint32_t e = c1;
      holders.clear();
      for (int u = 0; u < threads; ++u) {
        const auto [first, last] = range_[u];
        if (first <= c && c < last) {
          holders.push_back(u);
          e = std::min(e, last);
        } else if (c < first) {
          e = std::min(e, first);
        }
      }
      // Most stretches have one holder (every stretch at T = 1): a loop of its own, without the
      // loop over the holders (the slow crowd's index 5% faster).
      if (holders.size() == 1) {
        for (std::uint32_t* h = hist(holders[0]); c < e; ++c) {
          const std::uint32_t count = h[c];
          h[c] = run;
          run += count;
          end_[c] = run;
        }
      }
      for (; c < e; ++c) {
        for (const int u : holders) {
          std::uint32_t& h = hist(u)[c];
          const std::uint32_t count = h;
          h = run;
          run += count;
        }
        end_[c] = run;
      }
    }
  }

  // The copy's arrays start unwritten (Uninitialized): the entries a span's last group reads past
  // the binned ones get values, though no lane of them counts.
  void pad_copy() {
    for (auto* v : {&x_, &y_}) std::fill_n(v->begin() + binned_, kSpanPadding, 0.0);
    if (velocities_)
      for (auto* v : {&ux_, &uy_}) std::fill_n(v->begin() + binned_, kSpanPadding, 0.0);
    std::fill_n(id_.begin() + binned_, kSpanPadding, 0u);
  }

  int n_ = 1;
  double inverse_cell_ = 0, cell_side_ = 0;
  std::uint32_t binned_ = 0;
  bool velocities_ = true;
  Uninitialized<std::uint32_t> histogram_;  // per thread, then its scatter cursors
  Uninitialized<std::uint32_t> end_;        // end_[c]: one past the last position of cell c
  Uninitialized<std::uint32_t> cell_of_;    // by id
  std::vector<std::uint32_t> chunk_total_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> range_;  // per thread: its cells (build)
  Uninitialized<double> x_, y_, ux_, uy_;                       // by position (cell order)
  Uninitialized<std::uint32_t> id_;                             // by position
};

}  // namespace particle::detail
