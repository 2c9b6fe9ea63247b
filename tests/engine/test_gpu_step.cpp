// The GPU engine's algorithm (gpu/parallel_step.hpp) run on the host by its sequential twin
// (gpu/host_executor.hpp): the same stage functions the device runs. Its filter by rounds accepts
// exactly what the sequential filter accepts, and whole runs give brute's state and counters.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "engines.hpp"
#include "gpu/host_executor.hpp"
#include "helpers.hpp"
#include "particle/describe.hpp"
#include "step/stages.hpp"

namespace particle {
namespace {

using detail::gpu::HostExecutor;
using particle::Candidate;
using testing::Outcome;
using testing::random_scene;
using testing::speeds;

RunReport run_host_twin(const detail::World& w, const RunOptions&,
                        const detail::PipelineParams& params) {
  HostExecutor exec;
  return detail::gpu::run_parallel(exec, w, params);
}

RunReport simulate_host_twin(Scene& scene, const RunOptions& options,
                             const StepObserver& observer) {
  return detail::simulate_with(scene, options, observer, run_host_twin);
}

Outcome host_twin(Scene scene, int slow_factor, WallStop wall_stop, Overlap overlap) {
  RunOptions options;
  options.engine = "gpu";
  options.slow_factor = slow_factor;
  options.wall_stop = wall_stop;
  options.overlap = overlap;
  RunReport report = simulate_host_twin(scene, options, {});
  return {state_hash(scene.particles), report};
}

void expect_twin_matches_brute(const Scene& scene, int slow_factor = 1,
                               WallStop wall_stop = WallStop::per_coordinate,
                               Overlap overlap = Overlap::approaching) {
  SCOPED_TRACE("K=" + std::to_string(slow_factor));
  const Outcome brute = testing::outcome(scene, "brute", 1, slow_factor, 8, wall_stop, overlap);
  const Outcome twin = host_twin(scene, slow_factor, wall_stop, overlap);
  testing::expect_same(twin, brute);
  EXPECT_LE(twin.report.counters.pair_tests, brute.report.counters.pair_tests);
  EXPECT_EQ(twin.report.physics.max_overlap, brute.report.physics.max_overlap);
  EXPECT_EQ(twin.report.physics.wall_impulse, brute.report.physics.wall_impulse);
  EXPECT_EQ(twin.report.engine, "gpu");
}

TEST(GpuHostTwin, MatchesBruteOnTheDefaultScene) {
  const Scene scene = random_scene(400, 4000, 1, 60, 11);
  expect_twin_matches_brute(scene);
  expect_twin_matches_brute(scene, 16);
}

TEST(GpuHostTwin, MatchesBruteOnADenseSceneWithDropsAndOverlaps) {
  const Scene scene = random_scene(600, 300, 2, 60, 42);
  const Outcome brute = testing::outcome(scene, "brute", 1);
  ASSERT_GT(brute.report.counters.dropped, 0u);
  ASSERT_GT(brute.report.counters.overlaps, 0u);
  expect_twin_matches_brute(scene);
  expect_twin_matches_brute(scene, 16);
}

// The other readings: receding overlaps collided at t = 0 (appended by the pair kernel), the
// whole motion stopped at a wall line, and both counted where the readings part.
TEST(GpuHostTwin, MatchesBruteUnderTheOtherReadings) {
  const Scene scene = random_scene(600, 300, 2, 60, 42);
  ASSERT_GT(testing::outcome(scene, "brute", 1).report.counters.receding_overlaps, 0u);
  expect_twin_matches_brute(scene, 1, WallStop::per_coordinate, Overlap::always);
  expect_twin_matches_brute(scene, 2, WallStop::whole_motion, Overlap::always);
}

// The 2019 default speeds in a small box: one cell, so slot k has N - 1 - k partners, cut into
// pieces of 128 (slot 0's 1499 partners into 12). Every pair is tested once, as brute tests it.
TEST(GpuHostTwin, MatchesBruteWhenOneCellsSlotsSpanManyPieces) {
  const Scene scene = random_scene(1500, 3000, 1, 6, 17);
  expect_twin_matches_brute(scene);
  const Outcome twin = host_twin(scene, 1, WallStop::per_coordinate, Overlap::approaching);
  EXPECT_EQ(twin.report.counters.pair_tests, 6u * 1500 * 1499 / 2);
}

TEST(GpuPieces, KeepTheScannedCountBelow2To32) {
  EXPECT_EQ(detail::gpu::piece_size(1000), 128u);
  EXPECT_EQ(detail::gpu::piece_size(1'000'000), 233u);  // 10^12 / (2^32 - 1 - 10^6), rounded up
  for (std::uint64_t n : {1'000ull, 5'000'000ull, 10'000'000ull, 60'000'000ull}) {
    const std::uint64_t piece = detail::gpu::piece_size(n);
    EXPECT_LT(n * ((n + piece - 1) / piece), std::uint64_t{1} << 32) << n;
  }
}

TEST(GpuHostTwin, MatchesBruteOnASlowCrowdInManyCells) {
  expect_twin_matches_brute(random_scene(3000, 400, 1, 30, 5, speeds(0.5, 1)));
}

TEST(GpuHostTwin, MatchesBruteWithAFewVeryFastAmongSlow) {
  Scene scene = random_scene(2000, 500, 1, 40, 8, speeds(0.2, 0.6));
  for (std::size_t i = 0; i < scene.size(); i += 400) {
    scene.particles.vx[i] = 150.0 + static_cast<double>(i) / 10;
    scene.particles.vy[i] = -90.0;
  }
  expect_twin_matches_brute(scene);
}

TEST(GpuHostTwin, MatchesBruteFasterThanTheBoxAndAtRest) {
  expect_twin_matches_brute(random_scene(200, 500, 1, 40, 6, speeds(400, 1200)));
  expect_twin_matches_brute(random_scene(500, 200, 1, 5, 2, speeds(0, 0)));
}

TEST(GpuHostTwin, MatchesBruteFarFromTheOriginOfAHugeBox) {
  Scene scene = random_scene(800, 120, 1, 40, 13, speeds(0.3, 1));
  scene.L = 1e12;
  for (std::size_t i = 0; i < scene.size(); ++i) {
    scene.particles.x[i] += 1e12 - 200;
    scene.particles.y[i] += 1e12 - 200;
  }
  expect_twin_matches_brute(scene);
}

TEST(GpuHostTwin, EveryPrintedTimeUnitMatchesBrute) {
  const Scene scene = random_scene(300, 600, 1, 12, 3, speeds(2, 20));
  for (int k : {1, 16})
    EXPECT_EQ(testing::unit_hashes(scene, "gpu", k, simulate_host_twin),
              testing::unit_hashes(scene, "brute", k))
        << "K=" << k;
}

// Candidates over few particles, with many equal times: long chains of contested candidates.
std::vector<Candidate> contested_candidates(std::mt19937_64& rng, std::uint32_t particles,
                                            std::size_t count) {
  std::vector<Candidate> c;
  std::uniform_int_distribution<std::uint32_t> who(0, particles - 1);
  std::uniform_int_distribution<int> when(0, 7), kind(0, 5);
  while (c.size() < count) {
    const double t = when(rng) / 7.0;
    const std::uint32_t i = who(rng), j = who(rng);
    const int k = kind(rng);
    if (k < 3) {
      c.push_back({t, i, kWallX + static_cast<std::uint32_t>(k)});
    } else if (i != j) {
      c.push_back({t, std::min(i, j), std::max(i, j)});
    }
  }
  // A particle has at most one wall candidate and a pair at most one: keep the first of each.
  std::vector<Candidate> unique;
  for (const Candidate& a : c)
    if (std::none_of(unique.begin(), unique.end(), [&](const Candidate& b) {
          return a.i == b.i && (is_wall(a) ? is_wall(b) : a.j == b.j);
        }))
      unique.push_back(a);
  return unique;
}

TEST(GpuRounds, AcceptExactlyWhatTheSequentialFilterAccepts) {
  std::mt19937_64 rng(7);
  std::uint64_t most_rounds = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::uint32_t particles = 2 + trial % 40;
    std::vector<Candidate> ordered =
        contested_candidates(rng, particles, 1 + static_cast<std::size_t>(trial) % 120);
    detail::order_candidates(ordered);
    std::vector<std::uint8_t> taken(particles, 0);
    std::vector<Candidate> want;
    filter_candidates(ordered, taken, want);

    HostExecutor exec;
    detail::gpu::Rounds<HostExecutor> rounds(exec, particles);
    // Shuffled storage, with index giving the order: as the device sorts indices, not candidates.
    std::vector<std::uint32_t> index(ordered.size());
    std::vector<Candidate> stored(ordered.size());
    std::vector<std::uint32_t> slot(ordered.size());
    for (std::uint32_t k = 0; k < slot.size(); ++k) slot[k] = k;
    std::shuffle(slot.begin(), slot.end(), rng);
    for (std::uint32_t rank = 0; rank < ordered.size(); ++rank) {
      stored[slot[rank]] = ordered[rank];
      index[rank] = slot[rank];
    }
    std::vector<std::uint8_t> marks(particles, 0);
    std::vector<Candidate> got(ordered.size());
    const std::uint32_t accepted = exec.read(
        rounds.accept(stored.data(), index.data(), static_cast<std::uint32_t>(ordered.size()),
                      marks.data(), got.data()));
    got.resize(accepted);
    const auto key = [](const Candidate& c) { return std::tuple(c.t, c.i, c.j); };
    std::sort(got.begin(), got.end(), [&](auto& a, auto& b) { return key(a) < key(b); });
    std::sort(want.begin(), want.end(), [&](auto& a, auto& b) { return key(a) < key(b); });
    ASSERT_EQ(got.size(), want.size()) << "trial " << trial;
    for (std::size_t k = 0; k < got.size(); ++k)
      EXPECT_EQ(key(got[k]), key(want[k])) << "trial " << trial;
    EXPECT_EQ(marks, taken) << "trial " << trial;
    most_rounds = std::max(most_rounds, rounds.rounds());
  }
  EXPECT_GT(most_rounds, 3u);  // the trials do reach chains that take several rounds
}

// The engine is declared like every other, and refused with its reason where this process cannot
// run it (no CUDA in the build, or no device): never a crash.
TEST(GpuEngine, IsDeclaredExactAndRefusedWithAReasonWhereItCannotRun) {
  const EngineInfo* info = find_engine_info("gpu");
  ASSERT_NE(info, nullptr);
  EXPECT_TRUE(info->exact);
  EXPECT_TRUE(info->matches_reference);
  EXPECT_TRUE(info->uses_param(Param::slow_factor));
  EXPECT_FALSE(info->uses_param(Param::threads));
  const std::string why = engine_unavailable("gpu");
  if (!why.empty()) {
    Scene scene = random_scene(10, 100, 1, 2, 1);
    try {
      testing::run(scene, "gpu", 1, 1, 1);
      ADD_FAILURE() << "gpu ran without a device";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()), "engine gpu: " + why);
    }
  }
  EXPECT_EQ(engine_unavailable("brute"), "");
}

}  // namespace
}  // namespace particle
