// A whole sub-step per engine, scene and thread count: run_pipeline over a batch of sub-steps on
// a private copy of the scene's state (it evolves from batch to batch, as in a run). The reported
// time is per sub-step (manual time); the counters are every stage time and counter the engine
// library declares (particle/describe.hpp), per sub-step, under their declared keys.
#include <vector>

#include "bench_scene.hpp"
#include "broad_phase/auto.hpp"
#include "broad_phase/brute.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/grid.hpp"
#include "broad_phase/sweep.hpp"
#include "particle/describe.hpp"
#include "step/pipeline.hpp"

namespace {

using namespace particle::detail;

template <class Broad>
void BM_SubStep(benchmark::State& st, const bench::SceneSpec* spec, Broad make(), int batch) {
  bench::State state(bench::state_of(*spec));
  PipelineParams params;
  params.steps = batch;
  params.slow_factor = 1;  // the state holds per-sub-step displacements already
  params.threads = static_cast<int>(st.range(0));
  params.profile = true;
  const auto metrics = particle::metrics();
  const auto summed = [](const particle::MetricInfo& m) {
    return m.kind == particle::MetricKind::stage_time || m.kind == particle::MetricKind::counter;
  };
  std::vector<double> sum(metrics.size());
  std::uint64_t substeps = 0;
  std::string engine;
  for (auto _ : st) {
    Broad broad = make();
    const particle::RunReport report = run_pipeline(broad, state.w, params);
    st.SetIterationTime(report.wall_s / batch);
    for (std::size_t i = 0; i < metrics.size(); ++i) {
      if (!summed(metrics[i])) continue;
      const particle::MetricValue v = metrics[i].value(report);
      sum[i] +=
          v.type == particle::MetricValue::Type::count ? static_cast<double>(v.count) : v.real;
    }
    substeps += batch;
    engine = report.engine;
  }
  const double per = 1.0 / static_cast<double>(substeps);
  for (std::size_t i = 0; i < metrics.size(); ++i)
    if (summed(metrics[i])) st.counters[std::string(metrics[i].key)] = sum[i] * per;
  st.SetLabel(engine);
}

BruteBroadPhase make_brute() { return {}; }
template <int G>
GridBroadPhase make_grid() {
  return GridBroadPhase(G);
}
CellsBroadPhase make_cells() { return {}; }
SweepBroadPhase make_sweep() { return {}; }
AutoBroadPhase make_auto() { return {}; }

template <class Broad>
void add(const char* engine, Broad make(), const bench::SceneSpec& spec, int batch,
         std::initializer_list<int> threads) {
  const std::string name = std::string("BM_SubStep/") + engine + "/" + spec.name;
  auto* b = benchmark::RegisterBenchmark(name.c_str(), BM_SubStep<Broad>, &spec, make, batch);
  // The manual time is per sub-step, 1/batch of the real time: scale the minimum time to match.
  bench::with_min(b)
      ->ArgName("T")
      ->UseManualTime()
      ->Unit(benchmark::kMicrosecond)
      ->MinTime(0.1 / batch);
  for (int t : threads) b->Arg(t);
}

const bool registered = [] {
  using bench::kCrowd, bench::kDefault, bench::kMillion, bench::kSec8;
  // The default scene: brute at T = 1, 2 (issue 2) and every engine.
  add("brute", make_brute, kDefault, 20, {1, 2});
  add("grid8", make_grid<8>, kDefault, 20, {1, 2});
  add("sweep", make_sweep, kDefault, 20, {1, 2});
  add("cells", make_cells, kDefault, 20, {1, 2});
  add("auto", make_auto, kDefault, 20, {1, 2});
  // The report's section 8 scene (K = 4): brute, auto and grid at several G.
  add("brute", make_brute, kSec8, 8, {1, 2});
  add("auto", make_auto, kSec8, 32, {1, 2});
  add("grid1", make_grid<1>, kSec8, 8, {2});
  add("grid4", make_grid<4>, kSec8, 16, {2});
  add("grid16", make_grid<16>, kSec8, 32, {2});
  add("grid64", make_grid<64>, kSec8, 32, {2});
  // The slow crowd: brute against cells.
  add("brute", make_brute, kCrowd, 1, {2});
  add("cells", make_cells, kCrowd, 10, {1, 2});
  add("sweep", make_sweep, kCrowd, 10, {2});
  add("auto", make_auto, kCrowd, 10, {2});
  // One million particles: cells and auto only.
  add("cells", make_cells, kMillion, 2, {1, 2});
  add("auto", make_auto, kMillion, 2, {2});
  return true;
}();

}  // namespace
