// The wait policy psim chooses before the OpenMP runtime starts.
#include <gtest/gtest.h>
#include <omp.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

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

// spread_team: thread t, right after it, on the t-th CPU past the master's (modulo the CPUs), and
// none leaves before the whole team is in. Four threads a CPU, so the kernel's own placement of
// new threads matches this by chance only rarely; the kernel may move a thread again as soon as
// spread_team lets it (under ctest -j2 it did, once), so one team of five attempts must match.
TEST(WaitPolicy, SpreadTeamPutsThreadTOnTheTthCpuPastTheMasters) {
  if (omp_get_proc_bind() != omp_proc_bind_false) GTEST_SKIP() << "OMP_PROC_BIND is set";
  cpu_set_t all;
  ASSERT_EQ(sched_getaffinity(0, sizeof all, &all), 0);
  std::vector<int> cpus;  // the process's CPUs in order
  for (int id = 0; id < CPU_SETSIZE; ++id)
    if (CPU_ISSET(id, &all)) cpus.push_back(id);
  if (cpus.size() < 2) GTEST_SKIP() << "one CPU";
  const int threads = 4 * static_cast<int>(cpus.size());
  int matched = 0;
  for (int attempt = 0; attempt < 5 && matched == 0; ++attempt) {
    std::vector<int> on(static_cast<std::size_t>(threads), -1);
    std::vector<int> arrived_when_done(static_cast<std::size_t>(threads), 0);
    std::atomic<int> arrived{0};
    const int first_cpu = sched_getcpu();
#pragma omp parallel num_threads(threads)
    {
      const auto t = static_cast<std::size_t>(omp_get_thread_num());
      spread_team(arrived, first_cpu);
      on[t] = sched_getcpu();
      arrived_when_done[t] = arrived.load();
    }
    for (int n : arrived_when_done) EXPECT_EQ(n, threads);
    const auto first =
        static_cast<std::size_t>(std::find(cpus.begin(), cpus.end(), first_cpu) - cpus.begin());
    bool all_match = true;
    for (std::size_t t = 1; t < on.size(); ++t)
      all_match = all_match && on[t] == cpus[(first + t) % cpus.size()];
    matched += all_match ? 1 : 0;
  }
  EXPECT_EQ(matched, 1) << "no team of 5 had every thread where spread_team puts it";
}

}  // namespace
}  // namespace particle
