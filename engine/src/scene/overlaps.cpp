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
#include <memory>
#include <utility>
#include <vector>

#include "particle/options.hpp"
#include "scene/disk_grid.hpp"

namespace particle {
namespace {

constexpr int kMaxDigitBits = 11;

// A disk's cell (high half) and index (low half): sorting the keys sorts by cell. A scene holds at
// most 10^8 particles (io/input.cpp), so both halves fit 32 bits.
using Key = std::uint64_t;
std::uint32_t cell_of(Key k) { return static_cast<std::uint32_t>(k >> 32); }
std::uint32_t id_of(Key k) { return static_cast<std::uint32_t>(k); }

// Arrays that are written whole before they are read: not zero-filled first (a std::vector's
// value-initialization is a sequential pass over 8 MB each at a million disks).
template <class T>
std::unique_ptr<T[]> for_overwrite(std::size_t n) {
  return std::make_unique_for_overwrite<T[]>(n);
}

// Least significant digit first, `bits` bits of cell in all: a stable sort of the n `keys` by cell.
void sort_by_cell(std::unique_ptr<Key[]>& keys, std::size_t n, int bits) {
  const int passes = (bits + kMaxDigitBits - 1) / kMaxDigitBits;
  if (passes == 0) return;  // one cell
  const int digit = (bits + passes - 1) / passes;
  const Key mask = (Key{1} << digit) - 1;
  std::unique_ptr<Key[]> other = for_overwrite<Key>(n);
  std::vector<std::uint32_t> next(std::size_t{1} << digit);
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = 32 + pass * digit;
    std::fill(next.begin(), next.end(), 0u);
    for (std::size_t i = 0; i < n; ++i) ++next[(keys[i] >> shift) & mask];
    std::uint32_t sum = 0;
    for (std::uint32_t& c : next) sum += std::exchange(c, sum);
    for (std::size_t i = 0; i < n; ++i) other[next[(keys[i] >> shift) & mask]++] = keys[i];
    keys.swap(other);
  }
}

// Adds `part`'s pairs to `into`, keeping the first pair of both.
void merge(Overlaps& into, const Overlaps& part) {
  if (part.pairs == 0) return;
  if (into.pairs == 0 ||
      std::pair(part.first_i, part.first_j) < std::pair(into.first_i, into.first_j)) {
    into.first_i = part.first_i;
    into.first_j = part.first_j;
  }
  into.pairs += part.pairs;
}

// The disks sorted by cell (their keys and positions): the overlapping pairs whose first disk in
// that order lies in [from, to), each disk against the rest of its cell and the cells after it.
struct SortedDisks {
  const detail::DiskCells& cells;
  std::uint32_t g;
  std::size_t n;
  const Key* keys;
  const double *x, *y;

  Overlaps pairs(std::size_t from, std::size_t to) const {
    Overlaps found;
    const auto test = [&](std::size_t a, std::size_t b) {
      if (!cells.closer(x[a], y[a], x[b], y[b])) return;
      const std::size_t i = std::min(id_of(keys[a]), id_of(keys[b]));
      const std::size_t j = std::max(id_of(keys[a]), id_of(keys[b]));
      merge(found, {1, i, j});
    };
    // `above`: the first disk whose cell is at least the first of the three above the current
    // cell; it only moves forward as the cells do, and starts at no later disk than that.
    std::size_t above = from;
    for (std::size_t a = from; a < to; ++a) {
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
};

// Below this many disks threads cost more than they save.
constexpr std::size_t kParallelDisks = 4096;

}  // namespace

Overlaps find_overlaps(const Scene& scene, int threads) {
  const Particles& p = scene.particles;
  const auto n = static_cast<std::int64_t>(p.size());
  const detail::DiskCells cells(scene.L, scene.contact_distance(), p.size());
  const auto g = static_cast<std::uint32_t>(cells.side());
  threads = resolve_threads(threads);
  if (p.size() < kParallelDisks) threads = 1;

  // The sort is sequential (11 of 52 ms at a million disks); what is around it runs on `threads`.
  std::unique_ptr<Key[]> keys = for_overwrite<Key>(p.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t i = 0; i < n; ++i) {
    const auto c = static_cast<Key>(cells.cell_of(p.y[i]) * g + cells.cell_of(p.x[i]));
    keys[i] = c << 32 | static_cast<Key>(i);
  }
  const std::uint64_t cell_count = std::uint64_t{g} * g;
  sort_by_cell(keys, p.size(), std::bit_width(cell_count - 1));
  const std::unique_ptr<double[]> x = for_overwrite<double>(p.size()),
                                  y = for_overwrite<double>(p.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t k = 0; k < n; ++k) {
    x[k] = p.x[id_of(keys[k])];
    y[k] = p.y[id_of(keys[k])];
  }

  // Four ranges per thread, so that a thread the OS deschedules holds up little.
  const SortedDisks sorted{cells, g, p.size(), keys.get(), x.get(), y.get()};
  const std::int64_t ranges = 4 * threads;
  std::vector<Overlaps> parts(static_cast<std::size_t>(ranges));
#pragma omp parallel for num_threads(threads) schedule(dynamic)
  for (std::int64_t k = 0; k < ranges; ++k)
    parts[k] = sorted.pairs(static_cast<std::size_t>(k * n / ranges),
                            static_cast<std::size_t>((k + 1) * n / ranges));
  Overlaps found;
  for (const Overlaps& part : parts) merge(found, part);
  return found;
}

}  // namespace particle
