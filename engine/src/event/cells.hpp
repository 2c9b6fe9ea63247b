#pragma once
// The event engine's cell grid: m x m square cells over [0, L]^2, each at least the contact
// distance wide, so a particle can only touch particles of its own and the 8 neighbouring cells.
// Membership is an intrusive singly linked list per cell (insert at the head; removal walks the
// cell's short list to its predecessor): the grid keeps a 4-byte link per particle, and the
// particle's cell (CellPos) lives in the caller's per-particle record. The lists live in an
// (m + 2)^2 array whose border cells stay empty, so a neighbourhood is nine fixed offsets without
// bounds checks. (Heads in tiles of 4 x 4 cells, a cache line each, save a tenth of the grid's
// cache misses but cost more in index arithmetic: 10% slower.) A particle changes cell only
// through a crossing event, whose time comes from crossing_time(), so its cell stays exact even
// where rounding puts its centre a hair past the boundary.
//
// Size: side >= s (1 + 1e-9) makes the neighbourhood rule hold despite rounding. Within that, the
// number of cells per particle c comes from a cost model per unit length a particle travels
// (cells_per_particle): small cells mean few pairs to test per prediction, large ones few cell
// crossings, each an event. Measured against the fixed rule before it (2 cells per particle, or
// the smallest cells where those are at most 3 per particle): the default scene (c = 0.5)
// 16.4 against 19.6 ms, N = 1000 at packing fraction 0.2 (c = 3.8, the contact limit) 0.425
// against 0.464 s, 0.05 (c = 3) 0.269 against 0.265 s, dense30 unchanged (the contact limit).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <vector>

#include "event/queue.hpp"

namespace particle::detail {

// A particle's cell, 0 to m - 1 along each axis: kept by the caller in the particle's own record
// (the event engine's queue entry), which its events read anyway, instead of a line of its own.
struct CellPos {
  std::uint16_t x = 0, y = 0;
};

class CellGrid {
 public:
  static constexpr double kMaxCellsPerAxis = 65534;  // a cell coordinate fits 16 bits

  CellGrid(double L, double s, std::size_t n) {
    const double by_contact = std::floor(L / (s * (1 + 1e-9)));
    const double count = static_cast<double>(std::max<std::size_t>(n, 1));
    const double c = cells_per_particle(L, s, count, by_contact * by_contact / count);
    const double by_cost = std::ceil(std::sqrt(c * count));
    m_ = static_cast<std::uint32_t>(
        std::max(1.0, std::min({by_contact, by_cost, kMaxCellsPerAxis})));
    side_ = L / m_;
    stride_ = m_ + 2;
    none_ = static_cast<std::uint32_t>(n);
    head_.assign(static_cast<std::size_t>(stride_) * stride_, none_);
    next_.assign(n + 1, none_);  // n: "nobody", whose next is nobody again
  }

  std::uint32_t cells_per_axis() const { return m_; }

  // Puts particle i in the cell holding (x, y), which it writes to `at`.
  void insert(std::uint32_t i, CellPos& at, double x, double y) {
    at = {static_cast<std::uint16_t>(axis_cell(x)), static_cast<std::uint16_t>(axis_cell(y))};
    std::uint32_t& h = head_[cell(at)];
    next_[i] = h;
    h = i;
  }

  // Position along a Z-order (Morton) curve of the cell holding (x, y): particles stored in this
  // order have their neighbours' state close by in memory.
  std::uint64_t spatial_key(double x, double y) const {
    return spread_bits(axis_cell(x)) | (spread_bits(axis_cell(y)) << 1);
  }

  // The time from now until the centre at (x, y) moving at (vx, vy) leaves its cell through a
  // side with a neighbour cell (the box's outer sides are wall events), and the crossing code.
  void crossing_time(CellPos at, double x, double y, double vx, double vy, double& t,
                     std::uint32_t& code) const {
    const double tx = axis_crossing(at.x, x, vx), ty = axis_crossing(at.y, y, vy);
    if (tx <= ty) {
      t = tx;
      code = vx > 0 ? kCrossXHigh : kCrossXLow;
    } else {
      t = ty;
      code = vy > 0 ? kCrossYHigh : kCrossYLow;
    }
  }

  // Moves particle i (in cell `at`) into the neighbour cell the crossing code names.
  void cross(std::uint32_t i, CellPos& at, std::uint32_t code) {
    std::uint32_t* link = &head_[cell(at)];
    while (*link != i) link = &next_[*link];
    *link = next_[i];
    if (code == kCrossXLow) --at.x;
    if (code == kCrossXHigh) ++at.x;
    if (code == kCrossYLow) --at.y;
    if (code == kCrossYHigh) ++at.y;
    std::uint32_t& h = head_[cell(at)];
    next_[i] = h;
    h = i;
  }

  // Writes to out[0 .. count) the particles of the cells that became neighbours of i's cell
  // when i crossed into it through `code`: the row or column of 3 beyond it in that direction
  // (the border's empty cells beyond the box's sides). Returns the count; out only grows.
  std::uint32_t new_neighbours(std::uint32_t i, CellPos at, std::uint32_t code,
                               std::vector<std::uint32_t>& out) const {
    const std::uint32_t c = cell(at);
    std::uint32_t beyond, along;  // the middle cell of the row beyond, and the step along it
    if (code == kCrossXLow || code == kCrossXHigh) {
      beyond = code == kCrossXHigh ? c + 1 : c - 1;
      along = stride_;
    } else {
      beyond = code == kCrossYHigh ? c + stride_ : c - stride_;
      along = 1;
    }
    Gather g(out);
    for (const std::uint32_t k : {beyond - along, beyond, beyond + along}) g.cell(*this, k, i);
    return g.count;
  }

  // The same for every particle j != i in i's cell (`at`) and the 8 around it.
  std::uint32_t neighbours(std::uint32_t i, CellPos at, std::vector<std::uint32_t>& out) const {
    const std::uint32_t c = cell(at);
    Gather g(out);
    for (const std::uint32_t row : {c - stride_, c, c + stride_})
      for (std::uint32_t k = row - 1; k <= row + 1; ++k) g.cell(*this, k, i);
    return g.count;
  }

 private:
  // Cells per particle, at most `limit` (the contact limit) and 4: the cheapest c by the cost of
  // a particle's travel per unit length,
  //   f(c) = (4/pi) sqrt(c n) (1 + 3 tau / c) + 4 sqrt(2) n s g (1 + 9 tau / c),
  // crossings of cells of side 1 / sqrt(c n) (n = N / L^2; 4/pi: the mean of |cos| + |sin| over
  // directions), each an event whose prediction tests the 3 new cells' 3 / c particles, plus two
  // predictions over 9 cells per collision (2 / lambda per unit length, lambda = 1 / (2 sqrt(2)
  // n s g) the mean free path, g Henderson's contact value), a pair test costing tau = 0.2 of an
  // event (fitted to the default scene's times at c = 0.5, 1, 2).
  static double cells_per_particle(double L, double s, double count, double limit) {
    constexpr double kTau = 0.2, kMax = 4;
    const double n = count / (L * L);
    const double eta = std::min(0.9, n * std::numbers::pi * s * s / 4);
    const double g = (1 - 7 * eta / 16) / ((1 - eta) * (1 - eta));
    const double per_collision = 4 * std::numbers::sqrt2 * n * s * g;
    const auto cost = [&](double c) {
      return 4 / std::numbers::pi * std::sqrt(c * n) * (1 + 3 * kTau / c) +
             per_collision * (1 + 9 * kTau / c);
    };
    const double top = std::min(limit, kMax);
    double best = top;
    for (const double c : {0.25, 0.5, 1.0, 2.0, 3.0})
      if (c < top && cost(c) < cost(best)) best = c;
    return best;
  }

  // The list head index of a cell, inside the empty border.
  std::uint32_t cell(CellPos at) const { return (at.y + 1u) * stride_ + (at.x + 1u); }
  // Appends the particles of cells other than i to a vector, keeping room for the first of up
  // to 9 more cells. A cell holds at most one particle nearly always: its first is written
  // unconditionally and counted if real (nobody is slot none_), so only the rare longer lists
  // take a branch that the predictor cannot guess.
  struct Gather {
    static constexpr std::uint32_t kRoom = 10;
    std::vector<std::uint32_t>& out;
    std::uint32_t* at;
    std::uint32_t count = 0;

    explicit Gather(std::vector<std::uint32_t>& v) : out(v) {
      if (out.size() < kRoom) out.resize(kRoom);
      at = out.data();
    }
    void cell(const CellGrid& g, std::uint32_t k, std::uint32_t i) {
      std::uint32_t j = g.head_[k];
      at[count] = j;
      count += (j != g.none_) & (j != i);
      for (j = g.next_[j]; j != g.none_; j = g.next_[j]) {
        if (out.size() < count + kRoom) {
          out.resize(2 * out.size());
          at = out.data();
        }
        at[count] = j;
        count += j != i;
      }
    }
  };

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

  std::uint32_t m_ = 1;
  std::uint32_t stride_ = 3;  // m + 2: a row of cells with its two border cells
  std::uint32_t none_ = 0;    // n: the end of a cell's list
  double side_ = 0;
  std::vector<std::uint32_t> head_;  // first particle of each cell, row-major with the border
  std::vector<std::uint32_t> next_;  // per particle, the next of its cell's list or none_
};

}  // namespace particle::detail
