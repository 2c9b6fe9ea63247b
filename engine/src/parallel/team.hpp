#pragma once
// The barrier and the single of the engines' OpenMP teams, in place of `#pragma omp barrier` and
// `#pragma omp single`: libgomp's barrier wakes its futex every time, sleepers or not, and on this
// project's VMs that system call is most of its cost (two threads on the 2-core AMD EPYC VM:
// 1.4 to 1.6 us a barrier against 0.23 us for TeamBarrier; a team of one paid about 1 us too).
// The default scene's sub-step has one barrier, the slow crowd's about seven.
//
// A team that runs broad phases installs a TeamBarrier for its threads (TeamScope, inside its
// parallel region); team_barrier() in any other team, a nested one included, is OpenMP's.
#include <omp.h>

#include <atomic>
#include <cstdint>

namespace particle::detail {

class TeamBarrier {
 public:
  // Spins as long as libgomp would before it yields and sleeps (GOMP_SPINCOUNT's 300,000, or
  // 1,000 once the team outnumbers the CPUs), or not at all under OMP_WAIT_POLICY=passive, which
  // psim sets when the cores are busy (wait_policy.hpp).
  explicit TeamBarrier(int threads);

  // Every thread of the team: returns once all have called it, with everything each wrote before
  // visible to all.
  void wait();

 private:
  static constexpr int kYields = 16;
  std::uint32_t threads_;
  int spins_ = 0;
  alignas(64) std::atomic<std::uint32_t> arrived_{0};
  alignas(64) std::atomic<std::uint32_t> generation_{0};
};

// The calling thread's team barrier and the nesting level of the team it belongs to.
struct InstalledBarrier {
  TeamBarrier* barrier = nullptr;
  int level = -1;
};
inline thread_local InstalledBarrier installed_barrier;

// Every thread of a team, inside its parallel region: team_barrier() uses `barrier` until the
// scope ends.
class TeamScope {
 public:
  explicit TeamScope(TeamBarrier& barrier) : saved_(installed_barrier) {
    installed_barrier = {&barrier, omp_get_level()};
  }
  ~TeamScope() { installed_barrier = saved_; }
  TeamScope(const TeamScope&) = delete;
  TeamScope& operator=(const TeamScope&) = delete;

 private:
  InstalledBarrier saved_;
};

// team: `#pragma omp barrier`.
void team_barrier();

// team: `#pragma omp single`, on thread 0.
template <class F>
void team_single(F&& f) {
  if (omp_get_thread_num() == 0) f();
  team_barrier();
}

}  // namespace particle::detail
