#pragma once
// Memory bandwidth: STREAM's triad (a[i] = b[i] + q c[i]: two doubles read and one written, 24
// bytes an element as STREAM counts them, the write-allocate read left out) and a plain memcpy of
// the same bytes beside it (the figure the triad is checked against), on T = 1 and on all CPUs.
// The arrays are sized to lie beyond the last-level cache where memory allows; where they cannot
// (a VM that reports the host's whole L3), the figure is the cache's and says so (beyond_llc).
#include <cstddef>
#include <cstdint>
#include <memory>

namespace ceilings {

class Arrays {
 public:
  // Three arrays of `elements` doubles each, first touched by `threads` threads in the order the
  // kernels use them (so each thread's part is where it runs).
  Arrays(std::size_t elements, int threads);
  std::size_t elements() const { return elements_; }
  double* a() { return a_.get(); }
  const double* b() const { return b_.get(); }
  const double* c() const { return c_.get(); }

 private:
  std::size_t elements_;
  std::unique_ptr<double[]> a_, b_, c_;
};

// One pass of the triad over the arrays on `threads` threads; bytes counted as STREAM does.
struct Moved {
  double seconds = 0;
  std::uint64_t bytes = 0;
};
Moved triad(Arrays& arrays, double q, int threads);
// One memcpy of b into a, each thread its contiguous part: 16 bytes an element (read, write).
Moved copy(Arrays& arrays, int threads);

// Elements per array: three arrays together 4 times the last-level cache, at most a quarter of
// `available_bytes` and at most 3 x 256 MiB, at least 3 x 8 MiB.
std::size_t elements_for(std::uint64_t llc_bytes, std::uint64_t available_bytes);

}  // namespace ceilings
