// Advance: every particle without an accepted collision moves (contact.hpp, advance_particle).
// O(N), independent per particle.
#include <algorithm>

#include "contact.hpp"
#include "step/stages.hpp"

namespace particle::detail {

void advance_free(const World& w, const std::vector<std::uint8_t>& taken, std::size_t first,
                  std::size_t last) {
  last = std::min(last, w.n);
  const std::uint8_t* flags = taken.data();
  // A local copy: a store to x[i] could alias the caller's World (its lo and hi are doubles),
  // which made GCC reload them and the pointers every iteration and keep the loop scalar.
  const World local = w;
  for (std::size_t i = first; i < last; ++i) {
    // A conditional store, never a select that writes back: with a shared state the particles
    // with a collision are being moved by resolve on other threads at the same time. (With
    // AVX-512 this vectorizes as masked stores.)
    if (flags[i] == 0) advance_particle(local, i);
  }
}

}  // namespace particle::detail
