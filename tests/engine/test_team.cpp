// The engines' team barrier, single and work split (parallel/team.hpp), in place of OpenMP's.
#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "parallel/team.hpp"

namespace particle::detail {
namespace {

// Each round every thread writes its slot, meets the others, and must then read every slot of
// this round: a barrier that let one thread through early shows as an old value.
int stale_reads(int threads, int rounds) {
  std::vector<std::atomic<int>> slot(static_cast<std::size_t>(threads));
  std::atomic<int> stale{0};
  Team team(threads);
#pragma omp parallel num_threads(threads)
  {
    const TeamScope scope(team);
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
  Team team(2);
#pragma omp parallel num_threads(2)
  {
    const TeamScope scope(team);
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

// Rounds of two team_for calls with no barrier between them (a sub-step's wall and pair pieces),
// of piece counts that differ from call to call, with thread `late` sleeping before it starts
// every tenth round: every piece of every call must run exactly once, and the others must have
// taken some of the late thread's pieces.
struct SplitCounts {
  int wrong = 0;       // pieces run other than once
  int taken_late = 0;  // of the late thread's share, taken by another thread
};

SplitCounts split_counts(int threads, int late, int rounds) {
  std::vector<std::vector<std::atomic<int>>> runs(2);
  std::vector<std::vector<int>> by(2);
  for (auto& r : runs) r = std::vector<std::atomic<int>>(static_cast<std::size_t>(rounds) * 300);
  std::atomic<int> taken_late{0};
  Team team(threads);
#pragma omp parallel num_threads(threads)
  {
    const TeamScope scope(team);
    const int t = omp_get_thread_num();
    for (int round = 0; round < rounds; ++round) {
      if (t == late && round % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
      for (int call = 0; call < 2; ++call) {
        const auto pieces = static_cast<std::uint32_t>(1 + (round * 7 + call * 131) % 300);
        team_for(pieces, [&](std::uint32_t piece) {
          ++runs[static_cast<std::size_t>(call)][static_cast<std::size_t>(round) * 300 + piece];
          const std::uint32_t late_first = pieces * static_cast<std::uint32_t>(late) /
                                           static_cast<std::uint32_t>(threads),
                              late_last = pieces * static_cast<std::uint32_t>(late + 1) /
                                          static_cast<std::uint32_t>(threads);
          taken_late += t != late && piece >= late_first && piece < late_last;
        });
      }
      team_barrier();
    }
  }
  SplitCounts counts;
  for (int call = 0; call < 2; ++call)
    for (int round = 0; round < rounds; ++round) {
      const auto pieces = static_cast<std::size_t>(1 + (round * 7 + call * 131) % 300);
      for (std::size_t piece = 0; piece < 300; ++piece)
        counts.wrong +=
            runs[static_cast<std::size_t>(call)][static_cast<std::size_t>(round) * 300 + piece]
                .load() != (piece < pieces ? 1 : 0);
    }
  counts.taken_late = taken_late.load();
  return counts;
}

TEST(TeamFor, EveryPieceRunsOnceAndALateThreadsPiecesGoToTheOthers) {
  const SplitCounts two = split_counts(2, 1, 400);
  EXPECT_EQ(two.wrong, 0);
  EXPECT_GT(two.taken_late, 0);
  const SplitCounts five = split_counts(5, 3, 200);  // more threads than this VM's cores
  EXPECT_EQ(five.wrong, 0);
  EXPECT_GT(five.taken_late, 0);
}

// One Team for many parallel regions (the mpi engine's, one region a sub-step): each region's
// calls are new calls, whose pieces all run once.
TEST(TeamFor, ATeamServesOneRegionAfterAnother) {
  std::vector<std::atomic<int>> runs(5 * 40);
  Team team(2);
  for (int region = 0; region < 5; ++region) {
#pragma omp parallel num_threads(2)
    {
      const TeamScope scope(team);
      team_for(40,
               [&](std::uint32_t piece) { ++runs[static_cast<std::size_t>(region) * 40 + piece]; });
    }
  }
  int wrong = 0;
  for (const auto& r : runs) wrong += r.load() != 1;
  EXPECT_EQ(wrong, 0);
}

// Outside an installed team (a nested team, or none) team_for is OpenMP's loop: still once each.
TEST(TeamFor, ANestedTeamSplitsItsOwnLoop) {
  std::atomic<int> wrong{0};
  Team team(2);
#pragma omp parallel num_threads(2)
  {
    const TeamScope scope(team);
    std::vector<int> runs(50);
#pragma omp parallel num_threads(1)
    team_for(50, [&](std::uint32_t piece) { ++runs[piece]; });
    for (int r : runs) wrong += r != 1;
  }
  EXPECT_EQ(wrong.load(), 0);
}

}  // namespace
}  // namespace particle::detail
