// The wait policy psim chooses before the OpenMP runtime starts.
#include <gtest/gtest.h>

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

TEST(WaitPolicy, MachineReadingsAreSane) {
  EXPECT_GE(available_cpus(), 1);
  EXPECT_GE(other_running_tasks(), 0);
}

}  // namespace
}  // namespace particle
