#include "parallel/team.hpp"

#include <strings.h>

#include <cstdlib>

#include "parallel/wait.hpp"
#include "particle/wait_policy.hpp"

namespace particle::detail {

TeamBarrier::TeamBarrier(int threads) : threads_(static_cast<std::uint32_t>(threads)) {
  const char* policy = std::getenv("OMP_WAIT_POLICY");
  if (policy && strcasecmp(policy, "passive") == 0)
    spins_ = 0;
  else
    spins_ = threads > available_cpus() ? 1000 : 300000;
}

// The generation is read before arriving: it cannot move until this thread has.
void TeamBarrier::wait() {
  const std::uint32_t generation = generation_.load(std::memory_order_acquire);
  if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == threads_) {
    arrived_.store(0, std::memory_order_relaxed);  // before the release below
    generation_.store(generation + 1, std::memory_order_release);
    generation_.notify_all();
    return;
  }
  wait_until(
      generation_, [&](std::uint32_t seen) { return seen != generation; }, spins_, kYields);
}

void team_barrier() {
  if (omp_get_num_threads() == 1) return;
  if (const InstalledBarrier b = installed_barrier; b.barrier && b.level == omp_get_level())
    b.barrier->wait();
  else {
#pragma omp barrier
  }
}

}  // namespace particle::detail
