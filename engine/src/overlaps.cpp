// find_overlaps (particle/overlaps.hpp): the disks radix-sorted by cell, then each disk against
// the rest of its cell and the cells after it (right, and the three above), so every pair is met
// once and memory is read in cell order. A scene file lists its particles in an order unrelated to
// their cells: a counting sort over the g * g cells (about one per disk) increments and scatters
// at random into arrays far beyond the caches, a sixth of a million-particle S = 0 run; the radix
// passes of at most 11 bits touch 2048 counters and write 2048 streams, which stay in cache.
#include "particle/overlaps.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <utility>
#include <vector>

#include "disk_grid.hpp"

namespace particle {
namespace {

constexpr int kMaxDigitBits = 11;

// A disk's cell (high half) and index (low half): sorting the keys sorts by cell. A scene holds at
// most 10^8 particles (input.cpp), so both halves fit 32 bits.
using Key = std::uint64_t;
std::uint32_t cell_of(Key k) { return static_cast<std::uint32_t>(k >> 32); }
std::uint32_t id_of(Key k) { return static_cast<std::uint32_t>(k); }

// Least significant digit first, `bits` bits of cell in all: a stable sort of `keys` by cell.
void sort_by_cell(std::vector<Key>& keys, int bits) {
  const int passes = (bits + kMaxDigitBits - 1) / kMaxDigitBits;
  if (passes == 0) return;  // one cell
  const int digit = (bits + passes - 1) / passes;
  const Key mask = (Key{1} << digit) - 1;
  std::vector<Key> other(keys.size());
  std::vector<std::uint32_t> next(std::size_t{1} << digit);
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = 32 + pass * digit;
    std::fill(next.begin(), next.end(), 0u);
    for (const Key k : keys) ++next[(k >> shift) & mask];
    std::uint32_t sum = 0;
    for (std::uint32_t& c : next) sum += std::exchange(c, sum);
    for (const Key k : keys) other[next[(k >> shift) & mask]++] = k;
    keys.swap(other);
  }
}

}  // namespace

Overlaps find_overlaps(const Scene& scene) {
  const Particles& p = scene.particles;
  const std::size_t n = p.size();
  const detail::DiskCells cells(scene.L, scene.contact_distance(), n);
  const auto g = static_cast<std::uint32_t>(cells.side());

  std::vector<Key> keys(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<Key>(cells.cell_of(p.y[i]) * g + cells.cell_of(p.x[i]));
    keys[i] = c << 32 | i;
  }
  const std::uint64_t cell_count = std::uint64_t{g} * g;
  sort_by_cell(keys, std::bit_width(cell_count - 1));
  std::vector<double> x(n), y(n);
  for (std::size_t k = 0; k < n; ++k) {
    x[k] = p.x[id_of(keys[k])];
    y[k] = p.y[id_of(keys[k])];
  }

  Overlaps found;
  const auto test = [&](std::size_t a, std::size_t b) {
    if (!cells.closer(x[a], y[a], x[b], y[b])) return;
    const std::size_t i = std::min(id_of(keys[a]), id_of(keys[b]));
    const std::size_t j = std::max(id_of(keys[a]), id_of(keys[b]));
    if (found.pairs++ == 0 || std::pair(i, j) < std::pair(found.first_i, found.first_j)) {
      found.first_i = i;
      found.first_j = j;
    }
  };
  // `above`: the first disk whose cell is at least the first of the three above the current cell;
  // it only moves forward as the cells do.
  std::size_t above = 0;
  for (std::size_t a = 0; a < n; ++a) {
    const std::uint32_t c = cell_of(keys[a]), cx = c % g;
    const std::uint32_t right = cx + 1 < g ? c + 1 : c;  // the last cell tested after a's
    for (std::size_t b = a + 1; b < n && cell_of(keys[b]) <= right; ++b) test(a, b);
    if (c / g + 1 == g) continue;  // the top row
    const std::uint32_t first = c + g - (cx > 0), last = c + g + (cx + 1 < g);
    while (above < n && cell_of(keys[above]) < first) ++above;
    for (std::size_t b = above; b < n && cell_of(keys[b]) <= last; ++b) test(a, b);
  }
  return found;
}

}  // namespace particle
