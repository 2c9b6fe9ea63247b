// The engines' team barrier and single (parallel/team.hpp), in place of OpenMP's.
#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <cstdlib>
#include <string>
#include <vector>

#include "parallel/team.hpp"

namespace particle::detail {
namespace {

// Each round every thread writes its slot, meets the others, and must then read every slot of
// this round: a barrier that let one thread through early shows as an old value.
int stale_reads(int threads, int rounds) {
  std::vector<std::atomic<int>> slot(static_cast<std::size_t>(threads));
  std::atomic<int> stale{0};
  TeamBarrier barrier(threads);
#pragma omp parallel num_threads(threads)
  {
    const TeamScope scope(barrier);
    const int t = omp_get_thread_num();
    for (int r = 1; r <= rounds; ++r) {
      slot[static_cast<std::size_t>(t)].store(r, std::memory_order_relaxed);
      team_barrier();
      for (const auto& s : slot) stale += s.load(std::memory_order_relaxed) != r;
      team_barrier();  // nobody writes round r + 1 before all have read round r
    }
  }
  return stale.load();
}

// With an environment variable set for the scope of one test.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (old_.empty())
      unsetenv(name_);
    else
      setenv(name_, old_.c_str(), 1);
  }

 private:
  const char* name_;
  std::string old_;
};

TEST(TeamBarrier, NoThreadLeavesBeforeAllHaveArrived) {
  const ScopedEnv spin("OMP_WAIT_POLICY", "active");  // the spin
  EXPECT_EQ(stale_reads(2, 20000), 0);  // a thread a core: more would spin out others' slices
}

TEST(TeamBarrier, SleepersAreWokenUnderThePassivePolicy) {
  const ScopedEnv passive("OMP_WAIT_POLICY", "passive");  // no spin: yields, then sleeps
  EXPECT_EQ(stale_reads(2, 2000), 0);
  EXPECT_EQ(stale_reads(5, 500), 0);  // more threads than this VM's cores
}

// team_single runs its function once, on thread 0, and every thread sees what it wrote; a team
// nested in the scope's (a team of one, as the relay's closers prepare in) does not wait on the
// outer team's barrier.
TEST(TeamBarrier, SingleRunsOnceAndNestedTeamsKeepTheirOwnBarrier) {
  std::atomic<int> runs{0}, wrong{0};
  int value = 0;
  TeamBarrier barrier(2);
#pragma omp parallel num_threads(2)
  {
    const TeamScope scope(barrier);
    for (int r = 1; r <= 1000; ++r) {
      team_single([&] {
        ++runs;
        wrong += omp_get_thread_num() != 0;
        value = r;
      });
      wrong += value != r;
#pragma omp parallel num_threads(1)
      team_single([&] { wrong += omp_get_num_threads() != 1; });
      team_barrier();  // nobody writes value for r + 1 before all have read it
    }
  }
  EXPECT_EQ(runs.load(), 1000);
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace particle::detail
