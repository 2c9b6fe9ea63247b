// find_overlaps (particle/overlaps.hpp): the disks counting-sorted by cell, then each cell against
// itself and the four cells after it (right, and the three above), so every pair is met once and
// the memory is read in cell order (the linked lists of random placement, followed from a scene
// file in random order, missed the cache on every step: a third of a million-particle S = 0 run).
#include "particle/overlaps.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "disk_grid.hpp"

namespace particle {

Overlaps find_overlaps(const Scene& scene) {
  const Particles& p = scene.particles;
  const std::size_t n = p.size();
  const detail::DiskCells cells(scene.L, scene.contact_distance(), n);
  const std::int64_t g = cells.side();
  const auto cell = [&](std::size_t i) {
    return static_cast<std::size_t>(cells.cell_of(p.y[i]) * g + cells.cell_of(p.x[i]));
  };

  // A scene holds at most 10^8 particles (input.cpp), so 32-bit positions suffice.
  std::vector<std::uint32_t> start(static_cast<std::size_t>(g * g) + 1, 0), id(n);
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) ++start[cell(i) + 1];
  for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t k = next[cell(i)]++;
      id[k] = static_cast<std::uint32_t>(i);
      x[k] = p.x[i];
      y[k] = p.y[i];
    }
  }

  Overlaps found;
  const auto test = [&](std::uint32_t a, std::uint32_t b) {
    if (!cells.closer(x[a], y[a], x[b], y[b])) return;
    const std::size_t i = std::min(id[a], id[b]), j = std::max(id[a], id[b]);
    if (found.pairs++ == 0 || std::pair(i, j) < std::pair(found.first_i, found.first_j)) {
      found.first_i = i;
      found.first_j = j;
    }
  };
  constexpr std::array<std::array<std::int64_t, 2>, 4> kForward = {
      {{1, 0}, {-1, 1}, {0, 1}, {1, 1}}};
  for (std::int64_t cy = 0; cy < g; ++cy)
    for (std::int64_t cx = 0; cx < g; ++cx) {
      const std::size_t c = static_cast<std::size_t>(cy * g + cx);
      for (std::uint32_t a = start[c]; a < start[c + 1]; ++a) {
        for (std::uint32_t b = a + 1; b < start[c + 1]; ++b) test(a, b);
        for (const auto& [dx, dy] : kForward) {
          const std::int64_t nx = cx + dx, ny = cy + dy;
          if (nx < 0 || nx >= g || ny >= g) continue;
          const std::size_t d = static_cast<std::size_t>(ny * g + nx);
          for (std::uint32_t b = start[d]; b < start[d + 1]; ++b) test(a, b);
        }
      }
    }
  return found;
}

}  // namespace particle
