#pragma once
// The event engine's cell grid: m x m square cells over [0, L]^2, each at least the contact
// distance wide, so a particle can only touch particles of its own and the 8 neighbouring cells.
// Membership is an intrusive doubly linked list per cell (O(1) insert and remove, no allocation
// after construction); a particle changes cell only through a crossing event, whose time comes
// from crossing_time(), so its cell index stays exact even where rounding puts its centre a hair
// past the boundary.
//
// Size: side >= s (1 + 1e-9) makes the neighbourhood rule hold despite rounding. Dense scenes
// (at most kDenseCellsPerParticle cells of side s per particle: packing fraction above about
// 0.26) take the smallest cells, which leave the fewest pairs to test: their particles collide
// before they cross a cell, and a crossing tests only 3 cells. Dilute ones get about
// kCellsPerParticle per particle: else L^2/s^2 mostly empty cells and a crossing every s of
// travel. Measured (BM_Event): dense30 (2.6 cells per particle) 8-10% faster than at 2; the
// default scene 10% slower at 3 than at 2.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "event_queue.hpp"

namespace particle::detail {

class CellGrid {
 public:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  static constexpr double kCellsPerParticle = 2;
  static constexpr double kDenseCellsPerParticle = 3;

  CellGrid(double L, double s, std::size_t n) {
    const double by_contact = std::floor(L / (s * (1 + 1e-9)));
    const double count = static_cast<double>(n);
    const double by_count = by_contact * by_contact <= kDenseCellsPerParticle * count
                                ? by_contact
                                : std::ceil(std::sqrt(kCellsPerParticle * count));
    m_ = static_cast<std::uint32_t>(std::max(1.0, std::min(by_contact, by_count)));
    side_ = L / m_;
    head_.assign(static_cast<std::size_t>(m_) * m_, kNone);
    next_.assign(n, kNone);
    prev_.assign(n, kNone);
    cx_.assign(n, 0);
    cy_.assign(n, 0);
  }

  std::uint32_t cells_per_axis() const { return m_; }

  // Puts particle i in the cell holding (x, y).
  void insert(std::uint32_t i, double x, double y) {
    cx_[i] = axis_cell(x);
    cy_[i] = axis_cell(y);
    link(i);
  }

  // Position along a Z-order (Morton) curve of the cell holding (x, y): particles stored in this
  // order have their neighbours' state close by in memory.
  std::uint64_t spatial_key(double x, double y) const {
    return spread_bits(axis_cell(x)) | (spread_bits(axis_cell(y)) << 1);
  }

  // The time from now until the centre at (x, y) moving at (vx, vy) leaves its cell through a
  // side with a neighbour cell (the box's outer sides are wall events), and the crossing code.
  void crossing_time(std::uint32_t i, double x, double y, double vx, double vy, double& t,
                     std::uint32_t& code) const {
    const double tx = axis_crossing(cx_[i], x, vx), ty = axis_crossing(cy_[i], y, vy);
    if (tx <= ty) {
      t = tx;
      code = vx > 0 ? kCrossXHigh : kCrossXLow;
    } else {
      t = ty;
      code = vy > 0 ? kCrossYHigh : kCrossYLow;
    }
  }

  // Moves particle i into the neighbour cell the crossing code names.
  void cross(std::uint32_t i, std::uint32_t code) {
    unlink(i);
    if (code == kCrossXLow) --cx_[i];
    if (code == kCrossXHigh) ++cx_[i];
    if (code == kCrossYLow) --cy_[i];
    if (code == kCrossYHigh) ++cy_[i];
    link(i);
  }

  // Calls f(j) for every particle j in the cells that became neighbours of i's cell when i
  // crossed into it through `code`: the row or column of 3 beyond it in that direction.
  template <class F>
  void for_each_new_neighbour(std::uint32_t i, std::uint32_t code, F&& f) const {
    const bool along_x = code == kCrossXLow || code == kCrossXHigh;
    const std::uint32_t c = along_x ? cx_[i] : cy_[i];  // i's cell along the crossing axis
    const bool high = code == kCrossXHigh || code == kCrossYHigh;
    if (high ? c + 1 >= m_ : c == 0) return;  // the box's side: nothing beyond
    const std::uint32_t beyond = high ? c + 1 : c - 1;
    const std::uint32_t o = along_x ? cy_[i] : cx_[i];  // across the crossing axis
    const std::uint32_t o0 = o > 0 ? o - 1 : 0, o1 = std::min(o + 1, m_ - 1);
    for (std::uint32_t k = o0; k <= o1; ++k) {
      const std::uint32_t cell = along_x ? k * m_ + beyond : beyond * m_ + k;
      for (std::uint32_t j = head_[cell]; j != kNone; j = next_[j]) f(j);
    }
  }

  // Calls f(j) for every particle j != i in i's cell and the 8 around it.
  template <class F>
  void for_each_neighbour(std::uint32_t i, F&& f) const {
    const std::uint32_t x0 = cx_[i] > 0 ? cx_[i] - 1 : 0, x1 = std::min(cx_[i] + 1, m_ - 1);
    const std::uint32_t y0 = cy_[i] > 0 ? cy_[i] - 1 : 0, y1 = std::min(cy_[i] + 1, m_ - 1);
    for (std::uint32_t cy = y0; cy <= y1; ++cy)
      for (std::uint32_t cx = x0; cx <= x1; ++cx)
        for (std::uint32_t j = head_[cy * m_ + cx]; j != kNone; j = next_[j])
          if (j != i) f(j);
  }

 private:
  // Bit k of v moved to bit 2k.
  static std::uint64_t spread_bits(std::uint32_t v) {
    std::uint64_t x = v;
    x = (x | (x << 16)) & 0x0000FFFF0000FFFFull;
    x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
    x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
    x = (x | (x << 2)) & 0x3333333333333333ull;
    x = (x | (x << 1)) & 0x5555555555555555ull;
    return x;
  }
  std::uint32_t axis_cell(double x) const {
    return std::min(m_ - 1, static_cast<std::uint32_t>(std::max(0.0, x / side_)));
  }
  // Time to the cell's boundary in the direction of motion; infinite at the box's outer sides.
  double axis_crossing(std::uint32_t c, double x, double v) const {
    if (v > 0 && c + 1 < m_) return std::max(0.0, ((c + 1) * side_ - x) / v);
    if (v < 0 && c > 0) return std::max(0.0, (c * side_ - x) / v);
    return std::numeric_limits<double>::infinity();
  }
  void link(std::uint32_t i) {
    std::uint32_t& h = head_[cy_[i] * m_ + cx_[i]];
    prev_[i] = kNone;
    next_[i] = h;
    if (h != kNone) prev_[h] = i;
    h = i;
  }
  void unlink(std::uint32_t i) {
    if (prev_[i] != kNone)
      next_[prev_[i]] = next_[i];
    else
      head_[cy_[i] * m_ + cx_[i]] = next_[i];
    if (next_[i] != kNone) prev_[next_[i]] = prev_[i];
  }

  std::uint32_t m_ = 1;
  double side_ = 0;
  std::vector<std::uint32_t> head_;         // first particle of each cell, row-major
  std::vector<std::uint32_t> next_, prev_;  // per particle, within its cell's list
  std::vector<std::uint32_t> cx_, cy_;      // per particle, its cell
};

}  // namespace particle::detail
