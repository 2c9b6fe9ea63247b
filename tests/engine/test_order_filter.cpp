#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <random>

#include "parallel/team.hpp"
#include "step/stages.hpp"

namespace particle::detail {
namespace {

TEST(Order, TimeThenWallBeforePairThenIndices) {
  std::vector<Candidate> c = {{0.5, 3, 7}, {0.5, 9, kWallX}, {0.25, 8, 9},
                              {0.5, 2, 9}, {0.5, 2, 8},      {0.5, 4, kWallCorner}};
  order_candidates(c);
  const std::vector<std::pair<std::uint32_t, std::uint32_t>> expected = {
      {8, 9}, {4, kWallCorner}, {9, kWallX}, {2, 8}, {2, 9}, {3, 7}};
  ASSERT_EQ(c.size(), expected.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    EXPECT_EQ(c[k].i, expected[k].first) << k;
    EXPECT_EQ(c[k].j, expected[k].second) << k;
  }
}

TEST(Order, ResultDoesNotDependOnInputOrder) {
  std::mt19937_64 rng(3);
  std::vector<Candidate> c;
  for (std::uint32_t k = 0; k < 200; ++k)
    c.push_back({static_cast<double>(rng() % 4) / 4, k % 13, k % 3 ? 13 + k : kWallY});
  std::vector<Candidate> shuffled = c;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  order_candidates(c);
  order_candidates(shuffled);
  for (std::size_t k = 0; k < c.size(); ++k) {
    EXPECT_EQ(c[k].i, shuffled[k].i);
    EXPECT_EQ(c[k].j, shuffled[k].j);
  }
}

TEST(Filter, GreedyOneCollisionPerParticle) {
  const std::vector<Candidate> ordered = {{0.1, 1, kWallX}, {0.2, 0, 1}, {0.3, 0, 2},
                                          {0.4, 2, kWallY}, {0.5, 3, 4}, {0.6, 4, kWallX}};
  std::vector<std::uint8_t> taken(5, 0);
  std::vector<Candidate> accepted;
  filter_candidates(ordered, taken, accepted);
  ASSERT_EQ(accepted.size(), 3u);
  EXPECT_EQ(accepted[0].j, kWallX);  // 1 at the wall
  EXPECT_EQ(accepted[1].j, 2u);      // (0,1) dropped: 1 taken; (0,2) accepted
  EXPECT_EQ(accepted[2].i, 3u);      // 2's wall dropped; (3,4) accepted; 4's wall dropped
  EXPECT_EQ(std::count(taken.begin(), taken.end(), 1), 5);
}

// Distinct candidates as the broad phases give them (at most one wall per particle, each pair
// once, slot order within a pair), spread over three threads, with tied times.
std::vector<ThreadScratch> random_runs(std::mt19937_64& rng, std::uint32_t n) {
  std::vector<ThreadScratch> runs(3);
  std::vector<bool> wall(n, false), pair(n * n, false);
  for (int k = 0; k < 80; ++k) {
    const std::uint32_t a = static_cast<std::uint32_t>(rng() % n),
                        b = static_cast<std::uint32_t>(rng() % n);
    const double t = static_cast<double>(rng() % 4) / 4;
    Candidate c{t, std::min(a, b), std::max(a, b)};
    if (rng() % 3 == 0 || a == b) {
      if (wall[a]) continue;
      wall[a] = true;
      c = {t, a, kWallX + static_cast<std::uint32_t>(rng() % 3)};
    } else if (pair[c.i * n + c.j]) {
      continue;
    } else {
      pair[c.i * n + c.j] = true;
    }
    runs[rng() % 3].candidates.push_back(c);
  }
  return runs;
}

// The sub-step's selection by split_contested (lone candidates set apart, the rest ordered and
// filtered) accepts exactly what ordering and filtering every candidate accepts, in a run whose
// slots are a permutation of the particles (cell order) as in one in id order.
TEST(SplitContested, AcceptsWhatTheFullSortAndFilterAccept) {
  constexpr std::uint32_t n = 60;
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::uint32_t> id(n);  // slot -> particle
    for (std::uint32_t k = 0; k < n; ++k) id[k] = k;
    std::shuffle(id.begin(), id.end(), rng);
    const std::vector<ThreadScratch> runs = random_runs(rng, n);
    const auto in_ids = [&](Candidate c) {
      if (is_wall(c)) return Candidate{c.t, id[c.i], c.j};
      return Candidate{c.t, std::min(id[c.i], id[c.j]), std::max(id[c.i], id[c.j])};
    };

    std::vector<Candidate> all, want;
    for (const ThreadScratch& run : runs)
      for (const Candidate& c : run.candidates) all.push_back(in_ids(c));
    order_candidates(all);
    std::vector<std::uint8_t> taken(n, 0), uses(n, 0);
    filter_candidates(all, taken, want);

    std::vector<Candidate> uncontested, contested, got;
    split_contested(runs, false, uses, uncontested, contested, id.data());
    EXPECT_EQ(std::count(uses.begin(), uses.end(), 0), n) << "uses left set";
    EXPECT_EQ(uncontested.size() + contested.size(), all.size());
    std::vector<std::uint8_t> taken_split(n, 0);
    filter_candidates(contested, taken_split, got);
    accept_uncontested(uncontested, taken_split, got);
    for (std::uint32_t slot = 0; slot < n; ++slot) EXPECT_EQ(taken_split[slot], taken[id[slot]]);
    for (Candidate& c : got) c = in_ids(c);
    order_candidates(want);
    order_candidates(got);
    ASSERT_EQ(got.size(), want.size()) << "trial " << trial;
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].t, want[k].t);
      EXPECT_EQ(got[k].i, want[k].i);
      EXPECT_EQ(got[k].j, want[k].j);
    }
  }
}

// split_own_contested, each of a team's three threads splitting its own candidates, sets apart
// the candidates split_contested does (a particle in one candidate of each of two threads is
// contested), and leaves every count at zero.
TEST(SplitContested, OverTheTeamAsInOneThread) {
  constexpr std::uint32_t n = 60;
  std::mt19937_64 rng(9);
  const auto sorted = [](std::vector<Candidate> c) {
    order_candidates(c);
    return c;
  };
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<std::uint32_t> id(n);
    for (std::uint32_t k = 0; k < n; ++k) id[k] = k;
    std::shuffle(id.begin(), id.end(), rng);
    const std::vector<ThreadScratch> runs = random_runs(rng, n);
    std::vector<Candidate> uncontested, contested;
    std::vector<std::uint8_t> uses(n, 0);
    split_contested(runs, false, uses, uncontested, contested, id.data());

    std::vector<Selection> selections(runs.size());
    for (Selection& s : selections) s.uses.assign(n, 0);
    Team team(static_cast<int>(runs.size()));
#pragma omp parallel num_threads(static_cast <int>(runs.size()))
    {
      const TeamScope scope(team);
      split_own_contested(runs, selections, omp_get_thread_num(), false, id.data());
    }
    std::vector<Candidate> team_uncontested, team_contested;
    for (std::size_t t = 0; t < runs.size(); ++t) {
      const Selection& s = selections[t];
      EXPECT_EQ(std::count(s.uses.begin(), s.uses.end(), 0), n) << "uses left set, thread " << t;
      team_uncontested.insert(team_uncontested.end(), s.uncontested.begin(), s.uncontested.end());
      team_contested.insert(team_contested.end(), s.contested.begin(), s.contested.end());
    }
    for (const auto& [got, want] : {std::pair{sorted(team_uncontested), sorted(uncontested)},
                                    std::pair{sorted(team_contested), sorted(contested)}}) {
      ASSERT_EQ(got.size(), want.size()) << "trial " << trial;
      for (std::size_t k = 0; k < got.size(); ++k) {
        EXPECT_EQ(got[k].t, want[k].t);
        EXPECT_EQ(got[k].i, want[k].i);
        EXPECT_EQ(got[k].j, want[k].j);
      }
    }
  }
}

}  // namespace
}  // namespace particle::detail
