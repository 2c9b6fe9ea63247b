#pragma once
// What a rank's peak memory needs beyond freeing: glibc keeps freed blocks below its mmap
// threshold (which grows to the largest block freed, here arrays of a slot each) for the next
// malloc, so a freed array stays in the process's resident memory. The trim hands their pages
// back; the engine calls it where a large array is freed before a larger one is allocated (the
// distribution's order, the sub-steps' working memory before the end's gather).
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace particle::detail::mpi {

inline void return_freed_pages() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

}  // namespace particle::detail::mpi
