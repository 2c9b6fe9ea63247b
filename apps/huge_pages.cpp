// psim's global operator new: large blocks start just past a 2 MiB boundary and are advised as
// transparent huge pages (madvise: what the usual THP setting `madvise`, this VM's, waits for). A
// million-particle scene touches ~110 MB of fresh memory (the particle arrays, the overlap check's
// sort, the engine's working arrays): at 4 KiB a page that is ~27k page faults, a sixth of the
// whole run at S = 0; in 2 MiB pages ~60. Only the whole 2 MiB pages inside a block are advised, so
// the resident memory stays what is used. Smaller blocks, and the frees, are plain malloc/free:
// the default operator new's own calls (the array, nothrow, sized and aligned forms all end in
// these two or in aligned_alloc/free, which is the same heap).
//
// Each large block starts a different number of steps of 65 cache lines past its boundary: on
// the boundary itself, the state's arrays (x, y, velocities, counters: one block each) all began
// at one offset modulo the L1's and the L2's set periods, so a particle's seven values fell into
// one set of each, and the stages that touch them at one index (resolve, advance, the selection)
// evicted each other's lines. Staggered, those stages of the million-particle scene took 71
// against 83 ms at T = 1 and 40 against 49 ms at T = 2 (docs/performance.md, History). A
// staggered block's start is looked up in a table of the blocks given out when it is freed; a
// pointer at no step from a boundary is never one of them.
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
// Below this, a block holds one huge page at most: not worth it.
constexpr std::size_t kLargeBlock = 2 * kHugePage;
// The steps: 65 lines move a block one set on in the L1 (64 sets of 64 bytes) and 65 in the L2.
constexpr std::size_t kStep = 65 * 64, kSteps = 16;

// The large blocks given out: where each starts and the block malloc gave, which free() takes.
struct Given {
  void* start = nullptr;
  void* block = nullptr;
};
constexpr std::size_t kTable = 256;  // beyond this many live large blocks, no stagger
Given given[kTable];
std::mutex given_lock;
std::size_t next_step = 0;

// The large blocks alone: out of line, so that the small blocks' new and delete stay a test and
// a call of malloc or free (make regress counts a one-particle run's instructions).
[[gnu::noinline]] void* allocate_large(std::size_t size) {
  void* block = nullptr;
  if (posix_memalign(&block, kHugePage, size + kSteps * kStep) != 0) return nullptr;
  // Advice only: where the kernel has no huge page (or no THP), the block has small pages.
  madvise(block, (size + kSteps * kStep) & ~(kHugePage - 1), MADV_HUGEPAGE);
  const std::lock_guard lock(given_lock);
  for (Given& g : given)
    if (!g.start) {
      g = {static_cast<char*>(block) + kStep * (1 + next_step++ % kSteps), block};
      return g.start;
    }
  return block;  // on its boundary: freed as it is
}

// Frees p if it is a staggered block's start; `past` is its offset past its boundary less a step.
[[gnu::noinline]] bool release_large(void* p, std::size_t past) {
  if (past % kStep != 0) return false;
  const std::lock_guard lock(given_lock);
  for (Given& g : given)
    if (g.start == p) {
      std::free(g.block);
      g = {};
      return true;
    }
  return false;
}

void* allocate(std::size_t size) {
  if (size < kLargeBlock) return std::malloc(size == 0 ? 1 : size);
  return allocate_large(size);
}

void release(void* p) {
  // One compare leaves out every pointer but those 1 to kSteps steps past a 2 MiB boundary.
  const std::size_t past = (reinterpret_cast<std::uintptr_t>(p) & (kHugePage - 1)) - kStep;
  if (past < kSteps * kStep && release_large(p, past)) return;
  std::free(p);
}

}  // namespace

void* operator new(std::size_t size) {
  for (;;) {
    if (void* block = allocate(size)) return block;
    std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}

// The nothrow pair too (std::stable_sort's buffer comes from it): libstdc++'s own calls the
// form above, but a sanitizer's runtime replaces it with one of its own, whose blocks would then
// reach the delete below (AddressSanitizer: alloc-dealloc-mismatch, found by make test-sanitize).
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return operator new(size);
  } catch (const std::bad_alloc&) {
    return nullptr;
  }
}

void operator delete(void* block) noexcept { release(block); }
void operator delete(void* block, std::size_t) noexcept { release(block); }
void operator delete(void* block, const std::nothrow_t&) noexcept { release(block); }
