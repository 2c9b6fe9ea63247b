// Statistics and the ETA model: pure functions.
#include <gtest/gtest.h>

#include "results/stats.hpp"
#include "sweep/progress.hpp"

using namespace psweep;

TEST(Stats, MinMedianMax) {
  EXPECT_DOUBLE_EQ(minimum({3, 1, 2}), 1);
  EXPECT_DOUBLE_EQ(maximum({3, 1, 2}), 3);
  EXPECT_DOUBLE_EQ(median({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_DOUBLE_EQ(median({5}), 5);
  EXPECT_DOUBLE_EQ(median({7, 7, 1, 100, 7}), 7);
  EXPECT_DOUBLE_EQ(median({1e308, 1.5e308}),
                   1.25e308);  // no overflow in the mean of the middle pair
}

TEST(Stats, SummaryCountsOnlyOkRepetitionsOfThatConfig) {
  std::vector<RecordedRun> runs = {
      {"a", 0, true, 0.30},
      {"a", 1, true, 0.10},
      {"a", 2, false, std::nullopt},
      {"a", 3, true, 0.20},
      {"b", 0, true, 9.0},
      {"a", 4, false, 0.01},  // failed with a wall time: still not counted
  };
  Summary s = summarize(runs, "a");
  EXPECT_EQ(s.reps, 3);
  EXPECT_EQ(s.failed, 2);
  EXPECT_DOUBLE_EQ(*s.wall_min, 0.10);
  EXPECT_DOUBLE_EQ(*s.wall_median, 0.20);
  EXPECT_DOUBLE_EQ(*s.wall_max, 0.30);
  Summary none = summarize(runs, "c");
  EXPECT_EQ(none.reps, 0);
  EXPECT_EQ(none.failed, 0);
  EXPECT_FALSE(none.wall_min);
  Summary all_failed = summarize({{"x", 0, false, std::nullopt}}, "x");
  EXPECT_EQ(all_failed.failed, 1);
  EXPECT_FALSE(all_failed.wall_median);
}

TEST(Stats, BuildsPerSubstepFromTheMetricsCells) {
  EXPECT_DOUBLE_EQ(*builds_per_substep("40", "20", 4), 0.5);
  EXPECT_DOUBLE_EQ(*builds_per_substep("20", "20", std::nullopt), 1.0);  // K = 1 where unset
  EXPECT_DOUBLE_EQ(*builds_per_substep("3", "1.5", 2), 1.0);            // an interrupted run
  EXPECT_FALSE(builds_per_substep("", "20", 1));                        // a program's run
  EXPECT_FALSE(builds_per_substep("7", "", 1));
  EXPECT_FALSE(builds_per_substep("7x", "20", 1));
  EXPECT_FALSE(builds_per_substep("0", "0", 1));  // no sub-step reached
}

TEST(Stats, SummaryTakesTheFastestRepetitionsBuilds) {
  const std::vector<RecordedRun> runs = {
      {"a", 0, true, 0.30, false, 0.25},
      {"a", 1, true, 0.10, false, 0.5},
      {"a", 2, true, 0.20, false, 0.75},
      {"a", 3, false, 0.05, false, 1.0},  // failed: not counted
  };
  EXPECT_DOUBLE_EQ(*summarize(runs, "a").builds_per_substep, 0.5);
}

TEST(Stats, StateBandwidth) {
  EXPECT_DOUBLE_EQ(*state_gb_per_s(1e9, 4.8), 10.0);  // 48 GB in 4.8 s
  EXPECT_FALSE(state_gb_per_s(1e9, std::nullopt));
  EXPECT_FALSE(state_gb_per_s(1e9, 0.0));
  EXPECT_FALSE(state_gb_per_s(0, 1.0));  // N unknown (a scene file's)
}

TEST(Progress, EtaUsesPerConfigurationMeans) {
  std::vector<Job> jobs = {
      {0, 0, false}, {1, 0, false}, {0, 1, false}, {1, 1, false}, {2, 1, false}};
  EtaModel eta(3);
  EXPECT_DOUBLE_EQ(eta.remaining(jobs, 0), 0);  // nothing observed yet
  eta.add(0, 1.0);
  eta.add(1, 3.0);
  // remaining jobs 2..4: run 0 (1.0) + run 1 (3.0) + run 2 unseen (overall mean 2.0)
  EXPECT_DOUBLE_EQ(eta.remaining(jobs, 2), 6.0);
  EXPECT_DOUBLE_EQ(eta.remaining(jobs, 5), 0);
}

TEST(Progress, FormatDuration) {
  EXPECT_EQ(format_duration(0), "0:00");
  EXPECT_EQ(format_duration(65.4), "1:05");
  EXPECT_EQ(format_duration(3 * 3600 + 7 * 60 + 9), "3:07:09");
}
