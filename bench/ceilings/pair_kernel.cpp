#include "pair_kernel.hpp"

#include <omp.h>

#include <algorithm>
#include <memory>

#include "step/narrow_phase.hpp"

namespace ceilings {

using particle::detail::ThreadScratch;

KernelScene::KernelScene(std::uint32_t n)
    : x_(n),
      y_(n),
      ux_(n, 0.75),
      uy_(n, -0.5),
      impulse_(n),
      pair_collisions_(n),
      wall_collisions_(n) {
  // r = 1, so s = 2: particles 4 apart on a square lattice never touch, and equal displacements
  // make every relative displacement 0.
  std::uint32_t m = 1;  // the lattice's side
  while (m * m < n) ++m;
  for (std::uint32_t i = 0; i < n; ++i) {
    x_[i] = 10.0 + 4.0 * (i % m);
    y_[i] = 10.0 + 4.0 * (i / m);
  }
  w_ = particle::detail::make_world(20.0 + 4.0 * m, 1.0, n, x_.data(), y_.data(), ux_.data(),
                                    uy_.data(), pair_collisions_.data(), wall_collisions_.data(),
                                    impulse_.data());
}

KernelCount all_pairs(const KernelScene& scene, int passes) {
  const particle::detail::World& w = scene.world();
  const auto n = static_cast<std::uint32_t>(w.n);
  ThreadScratch out;
  KernelCount count;
  for (int pass = 0; pass < passes; ++pass) {
    out.clear_candidates();
    for (std::uint32_t i = 0; i + 1 < n; ++i) particle::detail::test_row(w, i, i + 1, n, out);
    count.candidates += out.candidates.size();
  }
  count.pair_tests = out.pair_tests;
  return count;
}

std::uint32_t particles_for_l1(std::uint64_t l1_bytes) {
  const std::uint64_t n = l1_bytes / (2 * 4 * sizeof(double));
  return static_cast<std::uint32_t>(std::clamp<std::uint64_t>(n, 64, 1024));
}

KernelTiming time_kernel(std::uint32_t n, int passes, int threads) {
  KernelTiming timing;
  double start = 0;
#pragma omp parallel num_threads(threads)
  {
    // Each thread's own scene, touched first by it: its own L1, its own cache lines.
    const auto scene = std::make_unique<KernelScene>(n);
    all_pairs(*scene, 1);  // warm: the scene in L1, the candidates' vector sized
#pragma omp barrier
#pragma omp master
    start = omp_get_wtime();
    const KernelCount count = all_pairs(*scene, passes);
#pragma omp barrier
#pragma omp master
    timing.seconds = omp_get_wtime() - start;
#pragma omp critical
    {
      timing.count.pair_tests += count.pair_tests;
      timing.count.candidates += count.candidates;
    }
  }
  return timing;
}

int vector_bits() {
#ifdef __AVX512F__
  return 512;
#elif defined(__AVX__)
  return 256;
#else
  return 128;  // SSE2: GCC lowers the 4-lane vectors to pairs of 2-lane registers
#endif
}

}  // namespace ceilings
