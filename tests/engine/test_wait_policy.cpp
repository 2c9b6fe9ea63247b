// The wait policy psim chooses before the OpenMP runtime starts.
#include <gtest/gtest.h>
#include <omp.h>
#include <sched.h>

#include <atomic>
#include <thread>

#include "helpers.hpp"
#include "particle/wait_policy.hpp"

namespace particle {
namespace {

TEST(WaitPolicy, PassiveWhenThreadsOutnumberCores) {
  const WaitPolicy p = choose_wait_policy(3, 2, 0);
  EXPECT_EQ(p.policy, "passive");
  EXPECT_EQ(p.reason, "oversubscribed");
}

TEST(WaitPolicy, PassiveWhenOtherTasksTakeTheCoresTheThreadsNeed) {
  const WaitPolicy p = choose_wait_policy(2, 2, 1);
  EXPECT_EQ(p.policy, "passive");
  EXPECT_EQ(p.reason, "loaded");
  EXPECT_EQ(choose_wait_policy(1, 2, 1).policy, "default");  // a free core remains
}

TEST(WaitPolicy, TheRuntimeDefaultOnAQuietMachine) {
  const WaitPolicy p = choose_wait_policy(2, 2, 0);
  EXPECT_EQ(p.policy, "default");
  EXPECT_EQ(p.reason, "quiet");
}

// The readings against what the test arranges: the CPUs this thread may use, and a task of its
// own that keeps running.
TEST(WaitPolicy, TheCpusAreTheThreadsAffinity) {
  cpu_set_t all;
  ASSERT_EQ(sched_getaffinity(0, sizeof all, &all), 0);
  EXPECT_EQ(available_cpus(), CPU_COUNT(&all));
  const cpu_set_t one = testing::first_cpu_of(all);
  ASSERT_EQ(sched_setaffinity(0, sizeof one, &one), 0);
  EXPECT_EQ(available_cpus(), 1);
  sched_setaffinity(0, sizeof all, &all);
}

TEST(WaitPolicy, ASpinningThreadIsAnotherRunningTask) {
  std::atomic<bool> stop{false};
  std::atomic<bool> started{false};
  std::thread spinner([&] {
    started = true;
    while (!stop) {
    }
  });
  while (!started) {
  }
  const int others = other_running_tasks();
  stop = true;
  spinner.join();
  EXPECT_GE(others, 1);  // runnable, on a core or waiting for one, in every sample
}

// Unbound (as ctest runs it), thread t counts as CPU t mod cpus; psim's
// PinnedThreadsUseEveryCoreWithEitherWaitPolicy covers the bound case.
TEST(WaitPolicy, ThreadsByCpuWithoutBinding) {
  if (omp_get_proc_bind() != omp_proc_bind_false) GTEST_SKIP() << "OMP_PROC_BIND is set";
  using Lists = std::vector<std::vector<int>>;
  EXPECT_EQ(threads_by_cpu(5, 2), (Lists{{0, 1}, {2, 3}, {4}}));
  EXPECT_EQ(threads_by_cpu(1, 4), (Lists{{0}}));
}

}  // namespace
}  // namespace particle
