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
