#pragma once
// How a thread of psim waits for another: a short spin, a few sched_yield()s, then a sleep on a
// futex (std::atomic::wait) until the awaited word changes. Whoever changes the word calls
// notify_all(), which in libstdc++ is a load and nothing more while nobody sleeps: on this
// project's VMs a futex call costs about a microsecond (libgomp's barrier makes one every time,
// parallel/team.hpp). Yielding alone is not enough on a shared core: the scheduler keeps
// running a yielding waiter as long as it is owed time, for up to a time slice, while the thread
// it waits for sits on the same core.
#include <sched.h>

#include <atomic>
#include <cstdint>

namespace particle::detail {

inline void cpu_pause() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Returns once ready(word) holds: `spins` pause iterations, then `yields` yields, then sleeps.
template <class Ready>
void wait_until(const std::atomic<std::uint32_t>& word, Ready ready, int spins, int yields) {
  for (int spin = 0;; ++spin) {
    const std::uint32_t seen = word.load(std::memory_order_acquire);
    if (ready(seen)) return;
    if (spin < spins)
      cpu_pause();
    else if (spin < spins + yields)
      sched_yield();
    else
      word.wait(seen, std::memory_order_acquire);
  }
}

}  // namespace particle::detail
