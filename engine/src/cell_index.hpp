#pragma once
// Cell index: particles counting-sorted into an n x n grid of square cells over [0, L]^2, in
// row-major cell order, with a contiguous copy of their values (CSR layout). The cells of one row
// are adjacent in memory, so "cells cx-k..cx+k of row cy" is one contiguous span that the narrow
// phase tests with one vectorized loop. Shared by the grid and cells broad phases.
//
// Build, O(N + cells) per sub-step, parallel and deterministic: each thread counts its static
// share of ids into its own histogram, the histograms are prefix-summed over (cell, thread), and
// each thread scatters its share again. Within a cell particles stay in id order for every thread
// count (the static shares are id ranges in thread order). Memory: 40 bytes per binned particle
// plus 4 bytes per cell per thread.
//
// Pair enumeration (half stencil with a reach of k cells): particle at position p of cell (cx, cy)
// is tested against [p+1, end of cell cx+k) in its own row and against cells cx-k..cx+k of rows
// cy+1..cy+k. Every pair of binned particles whose cells differ by at most k on both axes is
// tested exactly once: from the earlier one in CSR order in a shared row, else from the lower row.
#include <omp.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "narrow_phase.hpp"
#include "world.hpp"

namespace particle::detail {

class CellIndex {
 public:
  static constexpr std::uint32_t kNotBinned = 0xFFFFFFFFu;

  // single thread (or every thread with the same values): an n x n grid of cells of side L / n.
  void set_grid(int n, double L) {
    n_ = std::max(1, n);
    inverse_cell_ = n_ / L;
    cell_side_ = L / n_;
  }
  int n() const { return n_; }
  double cell_side() const { return cell_side_; }
  std::uint32_t cells() const { return static_cast<std::uint32_t>(n_) * n_; }

  // The cell column (or row) of coordinate x in [0, L]; rounding is covered by padded().
  int column(double x) const {
    const double c = x * inverse_cell_;  // clamped in double first: x +- reach may be far out
    return c <= 0 ? 0 : (c >= n_ - 1 ? n_ - 1 : static_cast<int>(c));
  }
  std::uint32_t cell_of(double x, double y) const {
    return static_cast<std::uint32_t>(column(y)) * n_ + column(x);
  }

  // team, barrier at the end. bin(i) is called once per particle on its thread's static share and
  // returns the particle's cell, or kNotBinned to leave it out of the index. before() runs on one
  // thread before anything else (it may call set_grid), after() on one thread at the end; both
  // ride on barriers the build needs anyway.
  template <class Before, class Bin, class After>
  void build(const World& w, Before&& before, Bin&& bin, After&& after) {
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
#pragma omp single
    {
      before();
      const std::uint32_t cells = this->cells();
      histogram_.resize(static_cast<std::size_t>(threads) * cells);
      end_.resize(cells);
      cell_of_.resize(w.n);
      chunk_total_.assign(threads, 0);
      if (x_.size() < w.n) {  // the copy is sized for every particle, binned or not
        x_.resize(w.n);
        y_.resize(w.n);
        ux_.resize(w.n);
        uy_.resize(w.n);
        id_.resize(w.n);
        cell_.resize(w.n);
      }
    }
    const std::uint32_t cells = this->cells();
    std::uint32_t* hist = histogram_.data() + static_cast<std::size_t>(t) * cells;
    std::fill(hist, hist + cells, 0u);
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < w.n; ++i) {
      const std::uint32_t c = bin(i);
      cell_of_[i] = c;
      if (c != kNotBinned) ++hist[c];
    }
    // Prefix over (cell, thread): thread t owns cells [c0, c1).
    const std::uint32_t c0 = static_cast<std::uint32_t>(std::uint64_t(cells) * t / threads);
    const std::uint32_t c1 = static_cast<std::uint32_t>(std::uint64_t(cells) * (t + 1) / threads);
    std::uint32_t total = 0;
    for (std::uint32_t c = c0; c < c1; ++c)
      for (int u = 0; u < threads; ++u) total += histogram_[std::size_t(u) * cells + c];
    chunk_total_[t] = total;
#pragma omp barrier
    std::uint32_t run = 0;
    for (int u = 0; u < t; ++u) run += chunk_total_[u];
    for (std::uint32_t c = c0; c < c1; ++c) {
      for (int u = 0; u < threads; ++u) {
        std::uint32_t& h = histogram_[std::size_t(u) * cells + c];
        const std::uint32_t count = h;
        h = run;
        run += count;
      }
      end_[c] = run;
    }
#pragma omp barrier
#pragma omp for schedule(static)
    for (std::size_t i = 0; i < w.n; ++i) {
      const std::uint32_t c = cell_of_[i];
      if (c == kNotBinned) continue;
      const std::uint32_t k = hist[c]++;
      x_[k] = w.x[i];
      y_[k] = w.y[i];
      ux_[k] = w.ux[i];
      uy_[k] = w.uy[i];
      id_[k] = static_cast<std::uint32_t>(i);
      cell_[k] = c;
    }
#pragma omp single
    {
      binned_ = end_[cells - 1];
      after();
    }
  }

  std::uint32_t binned() const { return binned_; }
  std::uint32_t begin(std::uint32_t c) const { return c ? end_[c - 1] : 0; }
  std::uint32_t end(std::uint32_t c) const { return end_[c]; }
  std::uint32_t cell_at(std::uint32_t k) const { return cell_[k]; }
  RowParticle particle(std::uint32_t k) const { return {x_[k], y_[k], ux_[k], uy_[k], id_[k]}; }
  SpanArrays arrays() const { return {x_.data(), y_.data(), ux_.data(), uy_.data(), id_.data()}; }

  // Tests the particle at position k against its half stencil of reach `reach` cells.
  void test_half_stencil(std::uint32_t k, int reach, double s2, ThreadScratch& out) const {
    const std::uint32_t c = cell_[k];
    const int cx = static_cast<int>(c % n_), cy = static_cast<int>(c / n_);
    const int lo = std::max(0, cx - reach), hi = std::min(n_ - 1, cx + reach);
    const RowParticle p = particle(k);
    const SpanArrays a = arrays();
    const std::uint32_t row = static_cast<std::uint32_t>(cy) * n_;
    test_span(p, a, k + 1, end_[row + hi], s2, out);
    const int top = std::min(n_ - 1, cy + reach);
    for (int ry = cy + 1; ry <= top; ++ry) {
      const std::uint32_t r = static_cast<std::uint32_t>(ry) * n_;
      test_span(p, a, begin(r + lo), end_[r + hi], s2, out);
    }
  }

  // Tests an outside particle (not binned) against every binned particle in the cells that
  // [x - reach_x, x + reach_x] x [y - reach_y, y + reach_y] touches.
  void test_box(const RowParticle& p, double reach_x, double reach_y, double s2,
                ThreadScratch& out) const {
    const int lo = column(p.x - reach_x), hi = column(p.x + reach_x);
    const int bottom = column(p.y - reach_y), top = column(p.y + reach_y);
    const SpanArrays a = arrays();
    for (int ry = bottom; ry <= top; ++ry) {
      const std::uint32_t r = static_cast<std::uint32_t>(ry) * n_;
      test_span(p, a, begin(r + lo), end_[r + hi], s2, out);
    }
  }

 private:
  int n_ = 1;
  double inverse_cell_ = 0, cell_side_ = 0;
  std::uint32_t binned_ = 0;
  std::vector<std::uint32_t> histogram_;  // per thread, then its scatter cursors
  std::vector<std::uint32_t> end_;        // end_[c]: one past the last position of cell c
  std::vector<std::uint32_t> cell_of_;    // by id
  std::vector<std::uint32_t> chunk_total_;
  std::vector<double> x_, y_, ux_, uy_;   // by position (cell order)
  std::vector<std::uint32_t> id_, cell_;  // by position
};

}  // namespace particle::detail
