// psim's global operator new: large blocks start on a 2 MiB boundary and are advised as
// transparent huge pages (madvise: what the usual THP setting `madvise`, this VM's, waits for). A
// million-particle scene touches ~110 MB of fresh memory (the particle arrays, the overlap check's
// sort, the engine's working arrays): at 4 KiB a page that is ~27k page faults, a sixth of the
// whole run at S = 0; in 2 MiB pages ~60. Only the whole 2 MiB pages inside a block are advised, so
// the resident memory stays what is used. Smaller blocks, and the frees, are plain malloc/free:
// the default operator new's own calls (the array, nothrow, sized and aligned forms all end in
// these two or in aligned_alloc/free, which is the same heap).
#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHugePage = std::size_t{2} << 20;
// Below this, a block holds one huge page at most: not worth it.
constexpr std::size_t kLargeBlock = 2 * kHugePage;

void* allocate(std::size_t size) {
  if (size < kLargeBlock) return std::malloc(size == 0 ? 1 : size);
  void* block = nullptr;
  if (posix_memalign(&block, kHugePage, size) != 0) return nullptr;
  // Advice only: where the kernel has no huge page (or no THP), the block has small pages.
  madvise(block, size & ~(kHugePage - 1), MADV_HUGEPAGE);
  return block;
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

void operator delete(void* block) noexcept { std::free(block); }
void operator delete(void* block, std::size_t) noexcept { std::free(block); }
void operator delete(void* block, const std::nothrow_t&) noexcept { std::free(block); }
