// Advance: every particle without an accepted collision moves (contact.hpp, advance_particle).
// O(N), independent per particle.
#include <algorithm>
#include <cstring>

#if defined(__AVX512F__) || defined(__AVX2__)
#include <immintrin.h>
#endif

#include "contact.hpp"
#include "step/stages.hpp"

namespace particle::detail {
namespace {

#ifdef __AVX512F__
// One coordinate of eight particles, the `free` lanes alone: move_clamped at t = 1 (u * 1 is u,
// and max/min against lo and hi pick what clamped() picks, lo and hi being positive).
[[gnu::always_inline]] inline void move8(double* x, const double* u, __mmask8 free, __m512d lo,
                                         __m512d hi) {
  const __m512d moved =
      _mm512_add_pd(_mm512_maskz_loadu_pd(free, x), _mm512_maskz_loadu_pd(free, u));
  _mm512_mask_storeu_pd(x, free, _mm512_min_pd(_mm512_max_pd(moved, lo), hi));
}
#endif

}  // namespace

void advance_free(const World& w, const std::vector<std::uint8_t>& taken, std::size_t first,
                  std::size_t last, [[maybe_unused]] bool owned) {
  last = std::min(last, w.n);
  const std::uint8_t* flags = taken.data();
  std::size_t i = first;
  // Only the free particles are read and written: with a shared state the particles with a
  // collision are being moved by resolve on other threads at the same time.
#ifdef __AVX512F__
  // Eight at a time, masked loads and stores. GCC's own vectorization of the loop below spilled
  // its masks and vectors to the stack: 4 ns a particle on the million-particle scene, a
  // quarter of the triad bandwidth.
  const __m512d lo = _mm512_set1_pd(w.lo), hi = _mm512_set1_pd(w.hi);
  for (; i + 8 <= last; i += 8) {
    const __mmask8 free = _mm_cmpeq_epi8_mask(
        _mm_loadl_epi64(reinterpret_cast<const __m128i*>(flags + i)), _mm_setzero_si128());
    move8(w.x + i, w.ux + i, free, lo, hi);
    move8(w.y + i, w.uy + i, free, lo, hi);
  }
#endif
  // A local copy: a store to x[i] could alias the caller's World (its lo and hi are doubles),
  // which made GCC reload them and the pointers every iteration and keep the loop scalar.
  const World local = w;
#if defined(__AVX2__) && !defined(__AVX512F__)
  // Four at a time where all four are free (nearly every group: a collision takes a particle in
  // a hundred on the slow crowd), else one by one: AVX2's masked store is slow on AMD's cores.
  // Where the state is owned, a group with a taken particle is stored whole, the taken lanes'
  // values blended back: on the default scene a particle in four meets a wall in a sub-step, two
  // groups in three hold one, and one by one the advance took 3.7 ns a particle.
  const __m256d lo = _mm256_set1_pd(w.lo), hi = _mm256_set1_pd(w.hi);
  const auto move4 = [&](double* x, const double* u, __m256d free) {
    const __m256d at = _mm256_loadu_pd(x);
    const __m256d moved =
        _mm256_min_pd(_mm256_max_pd(_mm256_add_pd(at, _mm256_loadu_pd(u)), lo), hi);
    _mm256_storeu_pd(x, _mm256_blendv_pd(at, moved, free));
  };
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  for (; i + 4 <= last; i += 4) {
    std::uint32_t four;
    std::memcpy(&four, flags + i, sizeof four);
    if (four == 0) {
      move4(local.x + i, local.ux + i, all);
      move4(local.y + i, local.uy + i, all);
    } else if (owned) {
      const __m256d free = _mm256_castsi256_pd(_mm256_cmpeq_epi64(
          _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(static_cast<int>(four))), _mm256_setzero_si256()));
      move4(local.x + i, local.ux + i, free);
      move4(local.y + i, local.uy + i, free);
    } else {
      for (std::size_t k = i; k < i + 4; ++k)
        if (flags[k] == 0) advance_particle(local, k);
    }
  }
#endif
  for (; i < last; ++i)
    if (flags[i] == 0) advance_particle(local, i);
}

}  // namespace particle::detail
