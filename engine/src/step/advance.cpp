// Advance: every particle without an accepted collision moves by its full displacement, clamped
// to [r, L-r] (only rounding can reach past a wall line, since a real crossing is a candidate).
// O(N), independent per particle.
#include <algorithm>

#include "step/stages.hpp"

namespace particle::detail {

void advance_free(const World& w, const std::vector<std::uint8_t>& taken, std::size_t first,
                  std::size_t last) {
  last = std::min(last, w.n);
  const std::uint8_t* flags = taken.data();
  for (std::size_t i = first; i < last; ++i) {
    // A conditional store, never a select that writes back: with a shared state the particles
    // with a collision are being moved by resolve on other threads at the same time. (With
    // AVX-512 this vectorizes as masked stores.)
    if (flags[i] == 0) {
      w.x[i] = move_clamped(w.x[i], w.ux[i], 1, w.lo, w.hi);
      w.y[i] = move_clamped(w.y[i], w.uy[i], 1, w.lo, w.hi);
    }
  }
}

}  // namespace particle::detail
