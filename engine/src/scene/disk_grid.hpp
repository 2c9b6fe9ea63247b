#pragma once
// Disks of one radius in a grid of g x g square cells at least s = 2r wide: every disk closer than
// s to a point lies in the 3 x 3 cells around it. Random placement (scene/draw_batch.hpp: a batch
// of draws sorted by cell, about four cells a disk, so that a draw's 3 x 3 cells hold a few
// entries) and the overlap check of a given scene (find_overlaps: all disks sorted by cell at once,
// about one cell a disk) both use this geometry: O(N) expected.
//
// The overlap test runs in a power-of-two unit near s (exact scaling, the same decisions as in the
// scene's units wherever those neither underflow nor overflow): s * s underflows to 0 for r below
// about 1e-162, and would then find no overlap at all.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>
#include <cstdint>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

namespace particle::detail {

class DiskCells {
 public:
  // About `per_disk` cells per disk for up to n disks in [0, L]^2, none narrower than s.
  DiskCells(double L, double s, std::size_t n, double per_disk = 1)
      : g_(static_cast<std::int64_t>(std::max(
            1.0,
            std::min(std::floor(L / s), std::ceil(std::sqrt(per_disk * static_cast<double>(n))))))),
        cell_(L / static_cast<double>(g_)),
        unit_(std::ldexp(1.0, -std::max(std::ilogb(s), DBL_MIN_EXP - 1))),
        s2_((s * unit_) * (s * unit_)) {}

  std::int64_t side() const { return g_; }
  std::int64_t cell_of(double c) const {
    return std::min(g_ - 1, static_cast<std::int64_t>(c / cell_));
  }
  // Centres (x1, y1) and (x2, y2) closer than s.
  bool closer(double x1, double y1, double x2, double y2) const {
    const double dx = (x1 - x2) * unit_, dy = (y1 - y2) * unit_;
    return dx * dx + dy * dy < s2_;
  }
#ifdef __AVX512F__
  // closer() in eight lanes, the same operations in each: those of `lanes` whose centres are
  // closer than s.
  __mmask8 closer(__mmask8 lanes, __m512d x1, __m512d y1, __m512d x2, __m512d y2) const {
    const __m512d unit = _mm512_set1_pd(unit_);
    const __m512d dx = _mm512_mul_pd(_mm512_sub_pd(x1, x2), unit);
    const __m512d dy = _mm512_mul_pd(_mm512_sub_pd(y1, y2), unit);
    return _mm512_mask_cmp_pd_mask(lanes,
                                   _mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                   _mm512_set1_pd(s2_), _CMP_LT_OQ);
  }
#endif

 private:
  std::int64_t g_;
  double cell_;
  double unit_;  // a power of two near 1/s
  double s2_;    // (s * unit)^2
};

}  // namespace particle::detail
