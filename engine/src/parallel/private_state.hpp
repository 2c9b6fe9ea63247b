#pragma once
// Private state: below kPrivateStateBelow particles every thread keeps its own copy of the
// particle state and applies every accepted collision and every free move to it, so no thread
// ever writes what another reads. A sub-step then needs one barrier (all candidates in) instead
// of two (all candidates in; all moves done), and broad phases build their structure per thread
// (no barrier either). The duplicated work is O(N) per thread and sub-step, about a microsecond
// per thousand particles: cheaper than a barrier once threads outnumber cores or a neighbour
// takes a core, and the copies cost 48 bytes per particle and thread.
//
// Every copy evolves bit for bit like the shared state would (same arithmetic on the same
// values), so the result is the same for every thread count and either mode.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "world.hpp"

namespace particle::detail {

inline constexpr std::size_t kPrivateStateBelow = 16384;

inline bool uses_private_state(std::size_t particles) { return particles < kPrivateStateBelow; }

// One thread's copy of a World's particle arrays.
class StateCopy {
 public:
  // Copies w's particles and returns a World over the copy (same box, same n).
  World copy_of(const World& w) {
    x_.assign(w.x, w.x + w.n);
    y_.assign(w.y, w.y + w.n);
    ux_.assign(w.ux, w.ux + w.n);
    uy_.assign(w.uy, w.uy + w.n);
    pair_.assign(w.pair_collisions, w.pair_collisions + w.n);
    wall_.assign(w.wall_collisions, w.wall_collisions + w.n);
    impulse_.assign(w.wall_impulse, w.wall_impulse + w.n);
    return over_arrays(w, w.n, x_.data(), y_.data(), ux_.data(), uy_.data(), pair_.data(),
                       wall_.data(), impulse_.data());
  }

  // Writes the copy back into w's arrays.
  void write_to(const World& w) const {
    std::copy(x_.begin(), x_.end(), w.x);
    std::copy(y_.begin(), y_.end(), w.y);
    std::copy(ux_.begin(), ux_.end(), w.ux);
    std::copy(uy_.begin(), uy_.end(), w.uy);
    std::copy(pair_.begin(), pair_.end(), w.pair_collisions);
    std::copy(wall_.begin(), wall_.end(), w.wall_collisions);
    std::copy(impulse_.begin(), impulse_.end(), w.wall_impulse);
  }

 private:
  std::vector<double> x_, y_, ux_, uy_, impulse_;
  std::vector<std::uint64_t> pair_, wall_;
};

}  // namespace particle::detail
