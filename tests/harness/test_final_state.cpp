// The last printed state of a program's output and how two of them differ: what a timed run is
// compared with its own print-mode run by.
#include <gtest/gtest.h>

#include <fstream>

#include "../scratch_folder.hpp"
#include "run/final_state.hpp"

using namespace psweep;

namespace {

std::string written(const std::string& name, const std::string& text) {
  const auto path = (test_support::scratch_folder("final-state") / name).string();
  std::ofstream(path) << text;
  return path;
}

// A print-mode output of `n` particles and `steps` time units, each value distinct.
std::string print_output(int n, int steps) {
  std::string text;
  for (int t = 0; t <= steps; ++t)
    for (int i = 0; i < n; ++i)
      text += std::to_string(t) + " " + std::to_string(i) + " " + std::to_string(t * 1000 + i) +
              ".00000000 1.00000000 2.00000000 3.00000000" + (t == steps ? " 4 5\n" : "\n");
  return text;
}

}  // namespace

TEST(FinalState, IsTheLastNLinesOfAnyLengthOfOutput) {
  // 2,001 states of 300 particles: 28 MB of lines read from the end, the tail growing past 4 KiB.
  const auto path = written("long.out", print_output(300, 2000));
  const auto last = final_state(path, 300);
  ASSERT_EQ(last.size(), 300u);
  EXPECT_EQ(last.front(), "2000 0 2000000.00000000 1.00000000 2.00000000 3.00000000 4 5");
  EXPECT_EQ(last.back(), "2000 299 2000299.00000000 1.00000000 2.00000000 3.00000000 4 5");
}

TEST(FinalState, IgnoresBlankLinesAndSpacingButNotValues) {
  const auto tidy = final_state(written("tidy.out", "0 0 1 2 3 4\n5 0 1 2 3 4 0 1\n"), 1);
  const auto spaced = final_state(written("spaced.out", "5  0\t1 2 3 4 0 1 \r\n\n\n"), 1);
  EXPECT_EQ(tidy, spaced);
  EXPECT_FALSE(final_state_difference(spaced, tidy, "in print mode"));
}

TEST(FinalState, ShortOrMissingOutputsGiveWhatTheyHave) {
  EXPECT_EQ(final_state(written("short.out", "5 0 1 2 3 4 0 0\n"), 3).size(), 1u);
  EXPECT_TRUE(final_state(written("empty.out", ""), 3).empty());
  EXPECT_TRUE(final_state("/nonexistent/output", 3).empty());
}

TEST(FinalState, TheFirstDifferenceNamesTheParticleAndBothLines) {
  const std::vector<std::string> print = {"5 0 1.0 2.0 3.0 4.0 1 0", "5 1 9.0 2.0 3.0 4.0 1 2"};
  const std::vector<std::string> idle = {"5 0 1.0 2.0 3.0 4.0 1 0", "5 1 8.0 2.0 3.0 4.0 0 0"};
  EXPECT_EQ(*final_state_difference(idle, print, "in print mode"),
            "particle 1: `5 1 8.0 2.0 3.0 4.0 0 0` here, `5 1 9.0 2.0 3.0 4.0 1 2` in print mode");
  EXPECT_EQ(*final_state_difference({print[0]}, print, "there"),
            "1 line of final state here, 2 there");
}
