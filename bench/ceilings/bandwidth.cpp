#include "bandwidth.hpp"

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <memory>

namespace ceilings {
namespace {

// Thread t's part [begin, end) of n elements split in `threads` contiguous parts.
std::pair<std::size_t, std::size_t> part(std::size_t n, int t, int threads) {
  const std::size_t per = (n + threads - 1) / threads;
  return {std::min(n, per * t), std::min(n, per * (t + 1))};
}

}  // namespace

Arrays::Arrays(std::size_t elements, int threads)
    : elements_(elements),
      a_(new double[elements]),
      b_(new double[elements]),
      c_(new double[elements]) {
  double* a = a_.get();
  double* b = b_.get();
  double* c = c_.get();
#pragma omp parallel num_threads(threads)
  {
    const auto [begin, end] = part(elements, omp_get_thread_num(), omp_get_num_threads());
    for (std::size_t i = begin; i < end; ++i) {
      a[i] = 0;
      b[i] = 1.0 + static_cast<double>(i % 7);
      c[i] = 0.5 * static_cast<double>(i % 5);
    }
  }
}

Moved triad(Arrays& arrays, double q, int threads) {
  double* a = arrays.a();
  const double* b = arrays.b();
  const double* c = arrays.c();
  const std::size_t n = arrays.elements();
  const double start = omp_get_wtime();
#pragma omp parallel num_threads(threads)
  {
    const auto [begin, end] = part(n, omp_get_thread_num(), omp_get_num_threads());
#pragma omp simd
    for (std::size_t i = begin; i < end; ++i) a[i] = b[i] + q * c[i];
  }
  return {omp_get_wtime() - start, 3 * sizeof(double) * n};
}

Moved copy(Arrays& arrays, int threads) {
  double* a = arrays.a();
  const double* b = arrays.b();
  const std::size_t n = arrays.elements();
  const double start = omp_get_wtime();
#pragma omp parallel num_threads(threads)
  {
    const auto [begin, end] = part(n, omp_get_thread_num(), omp_get_num_threads());
    std::memcpy(a + begin, b + begin, (end - begin) * sizeof(double));
  }
  return {omp_get_wtime() - start, 2 * sizeof(double) * n};
}

std::size_t elements_for(std::uint64_t llc_bytes, std::uint64_t available_bytes) {
  constexpr std::uint64_t MiB = 1 << 20;
  const std::uint64_t total = std::clamp<std::uint64_t>(
      std::min<std::uint64_t>(4 * llc_bytes, available_bytes / 4), 3 * 8 * MiB, 3 * 256 * MiB);
  return static_cast<std::size_t>(total / 3 / sizeof(double));
}

}  // namespace ceilings
