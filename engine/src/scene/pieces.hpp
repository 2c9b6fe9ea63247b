#pragma once
// The set-up's passes over an OpenMP team (random placement: scene/placement.cpp): pieces of work
// split into contiguous ranges a thread, run on the calling thread alone where one is asked, so
// that a one-particle run's instructions hold no OpenMP runtime (make regress).
#include <cstddef>
#include <cstdint>

namespace particle::detail {

// work(i) for i in [0, count) on `threads` threads.
template <class Work>
void for_pieces(int threads, std::size_t count, const Work& work) {
  if (threads <= 1 || count <= 1) {
    for (std::size_t i = 0; i < count; ++i) work(i);
    return;
  }
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t i = 0; i < static_cast<std::int64_t>(count); ++i)
    work(static_cast<std::size_t>(i));
}

}  // namespace particle::detail
