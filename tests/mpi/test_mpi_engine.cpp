// The mpi engine gives brute's bits (issue 43): the final state, every time unit's state and the
// counters and physics of brute at one thread, on scenes chosen for what crosses between ranks.
// ctest runs this binary alone (P = 1, no launcher) and under mpiexec at P = 2, 3, 4 and 8 (more
// ranks than cores), each scene at T = 1 and 2 threads per rank. Every rank builds the scene and
// runs brute; rank 0 runs mpi's simulate() and compares, the others follow it with their share.
// Built without MPI, it says why and exits 77, which ctest reports as skipped.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "../engine/helpers.hpp"
#include "particle/processes.hpp"

namespace particle {
namespace {

using testing::random_scene;
using testing::speeds;

Processes processes;  // set by main

struct Outcomes {
  testing::Outcome outcome;
  std::vector<std::uint64_t> units;  // the state hash after every time unit but the last
};

Outcomes run(Scene scene, const std::string& engine, int threads, int slow_factor,
             WallStop wall_stop = WallStop::per_coordinate,
             Overlap overlap = Overlap::approaching) {
  RunOptions options;
  options.engine = engine;
  options.threads = threads;
  options.slow_factor = slow_factor;
  options.wall_stop = wall_stop;
  options.overlap = overlap;
  std::vector<std::uint64_t> units;
  if (engine == "mpi" && !processes.leads()) return {{0, follow(options)}, units};
  const RunReport report = simulate(
      scene, options, [&](std::int64_t, const Particles& p) { units.push_back(state_hash(p)); });
  return {{state_hash(scene.particles), report}, units};
}

// mpi at T = 1 and 2 against brute at T = 1. The same calls on every rank: nothing here returns
// early on one rank only, which would leave the others waiting in a collective.
void expect_brutes_bits(const Scene& scene, int slow_factor = 1,
                        WallStop wall_stop = WallStop::per_coordinate,
                        Overlap overlap = Overlap::approaching) {
  const Outcomes brute = run(scene, "brute", 1, slow_factor, wall_stop, overlap);
  for (int threads : {1, 2}) {
    SCOPED_TRACE("P=" + std::to_string(processes.count) + " T=" + std::to_string(threads));
    const Outcomes mpi = run(scene, "mpi", threads, slow_factor, wall_stop, overlap);
    EXPECT_FALSE(mpi.outcome.report.interrupted);
    if (!processes.leads()) continue;  // a follower holds its share alone, and counts nothing
    testing::expect_same(mpi.outcome, brute.outcome);
    const RunReport &got = mpi.outcome.report, &want = brute.outcome.report;
    EXPECT_EQ(got.engine, "mpi");
    EXPECT_EQ(got.physics.max_overlap, want.physics.max_overlap);
    EXPECT_EQ(got.physics.energy_final, want.physics.energy_final);
    EXPECT_EQ(got.physics.wall_impulse, want.physics.wall_impulse);
    EXPECT_EQ(got.time_reached, want.time_reached);
    EXPECT_EQ(mpi.units, brute.units);
  }
}

// Particles given one per line: x y vx vy.
Scene scene_of(double L, double r, std::int64_t steps, const std::vector<std::vector<double>>& at) {
  Scene scene;
  scene.L = L;
  scene.r = r;
  scene.steps = steps;
  scene.particles = Particles(at.size());
  Particles& p = scene.particles;
  for (std::size_t i = 0; i < at.size(); ++i) {
    p.x[i] = at[i][0];
    p.y[i] = at[i][1];
    p.vx[i] = at[i][2];
    p.vy[i] = at[i][3];
  }
  return scene;
}

TEST(MpiMatchesBrute, DiluteRandomScene) {
  // The 2019 kind: speeds L/(8r) to L/4 per step.
  expect_brutes_bits(random_scene(300, 3000, 1, 20, 11));
}

TEST(MpiMatchesBrute, DenseScene) {
  const Scene scene = random_scene(400, 200, 2, 15, 42);
  const Outcomes brute = run(scene, "brute", 1, 1);
  ASSERT_GT(brute.outcome.report.counters.dropped, 0u);
  ASSERT_GT(brute.outcome.report.counters.overlaps, 0u);
  expect_brutes_bits(scene);
  expect_brutes_bits(random_scene(200, 150, 2, 4, 3), 4);  // and K = 4
}

TEST(MpiMatchesBrute, FasterThanTheBox) {
  // Up to three boxes per step: the halo reaches every rank.
  expect_brutes_bits(random_scene(150, 400, 1, 20, 6, speeds(400, 1200)));
}

TEST(MpiMatchesBrute, SlowCrowd) {
  expect_brutes_bits(random_scene(600, 300, 1, 15, 5, speeds(0.5, 1)));
}

// Each rank keeps its cells across sub-steps (mpi/pair_search.hpp) while particles cross the slab
// edges between its builds: the slots the exchange changes (arrivals, the last own particles moved
// into the slots of those that left, slots left empty and filled again) are tested apart until
// the next build. A rank builds about every fifth sub-step here (at most 20 of 40 asserted, so
// that the kept sub-steps are most of the run), at K = 1 and 2.
TEST(MpiMatchesBrute, SlowParticlesCrossSlabEdgesWhileTheCellsAreKept) {
  const Scene scene = random_scene(3000, 600, 1, 40, 9, speeds(0.5, 1));
  expect_brutes_bits(scene);
  expect_brutes_bits(scene, 2);
  const Outcomes mpi = run(scene, "mpi", 2, 1);
  if (processes.leads()) {
    EXPECT_GT(mpi.outcome.report.counters.broad_phase_builds, 1u);
    EXPECT_LE(mpi.outcome.report.counters.broad_phase_builds, 20u);
  }
}

// Every particle crosses every inner slab edge in every sub-step: lone ones at |vx| = L - 2r
// reach the far wall line at exactly t = 1 and bounce there, so they alternate between x = r and
// x = L - r; pairs in a row start at both walls and meet in the middle, where they swap.
TEST(MpiMatchesBrute, EveryParticleCrossesASlabEdgeEverySubStep) {
  std::vector<std::vector<double>> at;
  for (int row = 0; row < 30; ++row) {
    const double y = 2 + 3 * row, flip = row % 2 ? -1 : 1;
    if (row % 3 == 0) {
      at.push_back({1, y, 98, 0});
      at.push_back({99, y, -98, 0});
    } else {
      at.push_back({50 - 49 * flip, y, 98 * flip, 0});
    }
  }
  const Scene scene = scene_of(100, 1, 12, at);
  ASSERT_GT(run(scene, "brute", 1, 1).outcome.report.counters.pair_collisions, 0u);
  expect_brutes_bits(scene);
}

// A pair meets head-on across each edge that P = 2, 3, 4 or 8 slabs have (multiples of L/24),
// each in a row of its own, and a few oblique ones across the same edges.
TEST(MpiMatchesBrute, PairsCollideAcrossSlabEdges) {
  std::vector<std::vector<double>> at;
  for (int k = 1; k < 24; ++k) {
    const double edge = 240.0 * k / 24, y = 8.0 * k;
    at.push_back({edge - 3, y, 2, 0});
    at.push_back({edge + 3, y, -2, 0.5});
  }
  ASSERT_GT(run(scene_of(240, 1, 6, at), "brute", 1, 1).outcome.report.counters.pair_collisions,
            20u);
  expect_brutes_bits(scene_of(240, 1, 6, at));
}

// A row whose neighbours all approach (velocities fall along x) with gaps growing along it: every
// candidate shares a particle with the next and comes first, so the filter accepts one in two,
// from the left, one more per round: a chain of conflicts from slab 0 across three slabs and more.
TEST(MpiMatchesBrute, AChainOfConflictsSpansThreeSlabs) {
  std::vector<std::vector<double>> at;
  double x = 8;
  for (int k = 0; k < 40; ++k) {
    at.push_back({x, 50, (20 - k) * 0.5, 0});
    x += 2 + 0.01 * (k + 1);
  }
  const Scene scene = scene_of(100, 1, 6, at);
  const Outcomes brute = run(scene, "brute", 1, 1);
  ASSERT_GT(brute.outcome.report.counters.dropped, 15u);
  expect_brutes_bits(scene);
  expect_brutes_bits(testing::scene_from_file("cradle.in"));
}

TEST(MpiMatchesBrute, EveryParticleInOneSlab) {
  // All in [1, 11] x [2, 94] of a box of 100, slab 0 at every P here (below L/8): the other ranks
  // start empty.
  Scene scene = random_scene(120, 100, 1, 12, 7, speeds(0.5, 3));
  for (std::size_t i = 0; i < scene.size(); ++i) {
    scene.particles.x[i] = 1 + 2.5 * static_cast<double>(i % 5);
    scene.particles.y[i] = 2 + 4 * static_cast<double>(i / 5);
  }
  expect_brutes_bits(scene);
}

TEST(MpiMatchesBrute, MoreRanksThanSlabs) {
  // L = 10, s = 2: at most 5 slabs, so at P = 8 three ranks own nothing, ever.
  expect_brutes_bits(random_scene(6, 10, 1, 12, 4, speeds(1, 6)));
}

// The other wall-stop reading (docs/model.md), which changes how resolve moves a particle for the
// rest of its sub-step: the engine takes it with the run's World, as every field of the model.
TEST(MpiMatchesBrute, WholeMotionWallStop) {
  const Scene fast = random_scene(150, 400, 1, 12, 6, speeds(400, 1200));
  const Scene dense = random_scene(300, 150, 2, 12, 42);
  ASSERT_NE(run(fast, "brute", 1, 1, WallStop::whole_motion).outcome.hash,
            run(fast, "brute", 1, 1).outcome.hash);
  expect_brutes_bits(fast, 1, WallStop::whole_motion);
  expect_brutes_bits(dense, 2, WallStop::whole_motion);
}

// The overlap reading `always` adds each receding overlapping pair to the candidates at t = 0: on
// a rank border both ranks find it, as any crossing pair, and count it once.
TEST(MpiMatchesBrute, AlwaysOverlapReading) {
  const Scene dense = random_scene(300, 150, 2, 12, 42);
  ASSERT_NE(run(dense, "brute", 1, 1, WallStop::per_coordinate, Overlap::always).outcome.hash,
            run(dense, "brute", 1, 1).outcome.hash);
  expect_brutes_bits(dense, 1, WallStop::per_coordinate, Overlap::always);
  expect_brutes_bits(dense, 2, WallStop::whole_motion, Overlap::always);
}

TEST(MpiMatchesBrute, HandMadeScenes) {
  for (const char* file :
       {"head_on.in", "three_in_row_tie.in", "three_at_once.in", "four_at_centre.in",
        "wall_beats_pair.in", "corner.in", "wall_before_end.in", "crossing.in", "diagonal.in",
        "faster_than_box.in", "overlap_approaching.in", "overlap_receding.in",
        "too_fast_for_2019_grid.in"}) {
    SCOPED_TRACE(file);
    expect_brutes_bits(testing::scene_from_file(file));
  }
}

// A follower's failures, with its rank: its default printer is off, or every line would come P
// times.
class FollowerFailures : public ::testing::EmptyTestEventListener {
 public:
  explicit FollowerFailures(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& r) override {
    if (r.failed())
      std::printf("rank %d: %s:%d: %s\n", rank_, r.file_name() ? r.file_name() : "?",
                  r.line_number(), r.summary());
  }

 private:
  int rank_;
};

}  // namespace
}  // namespace particle

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  if (const std::string why = particle::engine_unavailable("mpi"); !why.empty()) {
    std::printf("skipped: the mpi engine: %s\n", why.c_str());
    return 77;
  }
  particle::processes = particle::join_processes();
  if (!particle::processes.leads()) {
    ::testing::TestEventListeners& listeners = ::testing::UnitTest::GetInstance()->listeners();
    delete listeners.Release(listeners.default_result_printer());
    listeners.Append(new particle::FollowerFailures(particle::processes.rank));
  }
  return RUN_ALL_TESTS();
}
