// The event engine's speed: pair collisions per second on one core (the figure event-driven codes
// are compared by), on the dense scene (N = 100,000 at packing fraction 0.3, the default
// speed law), on the same density with 10,000 disks (whose state, under 1 MB, fits in a core's L2
// cache: the gap between the two is the cost of memory latency) and on the default dilute scene.
// Each iteration predicts a fresh copy of the scene (untimed) and runs it to a horizon; the rates
// are per second of CPU time of the loop.
#include <cmath>

#include "bench_scene.hpp"
#include "event/simulation.hpp"

namespace {

using namespace particle::detail;

// N = 100,000 disks of radius 1 at packing fraction N pi r^2 / L^2 = 0.3.
const bench::SceneSpec kDense30{"dense30", 100000, std::sqrt(100000 * M_PI / 0.3), 1, 1, {}};
const bench::SceneSpec kSmall30{"small30", 10000, std::sqrt(10000 * M_PI / 0.3), 1, 1, {}};

void BM_Event(benchmark::State& st, const bench::SceneSpec* spec, double horizon) {
  std::uint64_t collisions = 0, events = 0, tests = 0, stale = 0;
  for (auto _ : st) {
    st.PauseTiming();
    bench::State state(bench::state_of(*spec));
    EventSimulation sim(state.w, spec->slow_factor);
    const particle::Counters before = sim.counters();
    st.ResumeTiming();
    sim.run_until(horizon);
    const particle::Counters& after = sim.counters();
    collisions += after.pair_collisions;
    events += after.candidates - before.candidates;
    tests += after.pair_tests - before.pair_tests;
    stale += sim.stale_events();
  }
  using benchmark::Counter;
  st.counters["collisions_per_s"] = Counter(static_cast<double>(collisions), Counter::kIsRate);
  st.counters["predictions_per_s"] = Counter(static_cast<double>(events), Counter::kIsRate);
  st.counters["tests_per_prediction"] = static_cast<double>(tests) / static_cast<double>(events);
  st.counters["predictions_per_collision"] =
      static_cast<double>(events) / static_cast<double>(collisions);
  st.counters["stale_per_collision"] = static_cast<double>(stale) / static_cast<double>(collisions);
}

const bool registered = [] {
  // dense30: about 8 million collisions per time unit; 0.05 of a unit is ~400,000 collisions.
  bench::with_min(benchmark::RegisterBenchmark("BM_Event/dense30", BM_Event, &kDense30, 0.05))
      ->Unit(benchmark::kMillisecond);
  bench::with_min(benchmark::RegisterBenchmark("BM_Event/small30", BM_Event, &kSmall30, 0.5))
      ->Unit(benchmark::kMillisecond);
  bench::with_min(benchmark::RegisterBenchmark("BM_Event/default", BM_Event, &bench::kDefault, 20))
      ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
