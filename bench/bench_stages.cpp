// Each pipeline stage alone on the first state of a scene: wall candidates, order, filter,
// resolve, advance, and per engine its broad phase (prepare: the structure) and narrow phase
// (find_pairs: its pairs through the exact test), at T = 1 and 2.
#include <omp.h>

#include "bench_scene.hpp"
#include "broad_phase/auto.hpp"
#include "broad_phase/bands.hpp"
#include "broad_phase/brute.hpp"
#include "broad_phase/cells.hpp"
#include "broad_phase/grid.hpp"
#include "broad_phase/sweep.hpp"
#include "step/stages.hpp"

namespace {

using namespace particle;
using namespace particle::detail;

const bench::SceneSpec* const kScenes[] = {&bench::kDefault, &bench::kSec8, &bench::kCrowd,
                                           &bench::kMillion};

// The sub-step's candidates (walls and brute's pairs), unordered, for order/filter/resolve.
const std::vector<Candidate>& candidates_of(const bench::SceneSpec& spec) {
  static std::vector<std::pair<const bench::SceneSpec*, std::vector<Candidate>>> cache;
  for (auto& [s, c] : cache)
    if (s == &spec) return c;
  const World& w = bench::state_of(spec).w;
  ThreadScratch out;
  find_wall_candidates(w, out);
  CellsBroadPhase cells;  // brute's set, found fast enough for a million particles
  cells.prepare(w);
  find_pairs(cells, w, out);
  cache.emplace_back(&spec, std::move(out.candidates));
  return cache.back().second;
}

void BM_WallCandidates(benchmark::State& st, const bench::SceneSpec* spec) {
  const World& w = bench::state_of(*spec).w;
  ThreadScratch out;
  for (auto _ : st) {
    out.clear_candidates();
    find_wall_candidates(w, out);
    benchmark::DoNotOptimize(out.candidates.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(w.n));
}

void BM_Order(benchmark::State& st, const bench::SceneSpec* spec) {
  const std::vector<Candidate>& unordered = candidates_of(*spec);
  std::vector<Candidate> c;
  for (auto _ : st) {
    c = unordered;  // a copy (memcpy) per iteration: sorting sorted input would flatter
    order_candidates(c);
    benchmark::DoNotOptimize(c.data());
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(unordered.size()));
  st.counters["candidates"] = static_cast<double>(unordered.size());
}

void BM_Filter(benchmark::State& st, const bench::SceneSpec* spec) {
  std::vector<Candidate> ordered = candidates_of(*spec);
  order_candidates(ordered);
  std::vector<std::uint8_t> taken(bench::state_of(*spec).w.n, 0);
  std::vector<Candidate> accepted;
  for (auto _ : st) {
    filter_candidates(ordered, taken, accepted);
    release_taken(accepted, taken);  // for the next iteration, as the pipeline does
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(ordered.size()));
}

void BM_Resolve(benchmark::State& st, const bench::SceneSpec* spec) {
  bench::State state(bench::state_of(*spec));  // resolve changes the state: a private copy
  std::vector<Candidate> ordered = candidates_of(*spec);
  order_candidates(ordered);
  std::vector<std::uint8_t> taken(state.w.n, 0);
  std::vector<Candidate> accepted;
  filter_candidates(ordered, taken, accepted);
  for (auto _ : st) resolve_collisions(state.w, accepted);  // repeats on a drifting state
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(accepted.size()));
}

void BM_Advance(benchmark::State& st, const bench::SceneSpec* spec) {
  bench::State state(bench::state_of(*spec));
  std::vector<std::uint8_t> taken(state.w.n, 0);
  for (auto _ : st) advance_free(state.w, taken);
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(state.w.n));
}

// prepare() alone, or prepare() + find_pairs() (reported as the narrow phase), on T threads.
template <class Broad>
void BM_Broad(benchmark::State& st, const bench::SceneSpec* spec, Broad make(), bool pairs) {
  const World& w = bench::state_of(*spec).w;
  const int threads = static_cast<int>(st.range(0));
  Broad broad = make();
  std::vector<ThreadScratch> scratch(threads);
  std::uint64_t tests = 0;
  for (auto _ : st) {
#pragma omp parallel num_threads(threads)
    {
      ThreadScratch& mine = scratch[omp_get_thread_num()];
      mine.clear_candidates();
      mine.pair_tests = 0;
      broad.prepare(w);
      if (pairs) find_pairs(broad, w, mine);
    }
  }
  for (const ThreadScratch& s : scratch) tests += s.pair_tests;
  st.counters["pair_tests"] = static_cast<double>(tests);
}

BruteBroadPhase make_brute() { return {}; }
GridBroadPhase make_grid() { return GridBroadPhase(8); }
CellsBroadPhase make_cells() { return {}; }
SweepBroadPhase make_sweep() { return {}; }
BandsBroadPhase make_bands() { return BandsBroadPhase(); }
AutoBroadPhase make_auto() { return {}; }

template <class Broad>
void register_broad(const char* engine, Broad make(), const bench::SceneSpec* spec) {
  for (bool pairs : {false, true}) {
    const std::string name =
        std::string(pairs ? "BM_BroadAndNarrow/" : "BM_BroadPrepare/") + engine + "/" + spec->name;
    bench::with_min(benchmark::RegisterBenchmark(name.c_str(), BM_Broad<Broad>, spec, make, pairs))
        ->ArgName("T")
        ->Arg(1)
        ->Arg(2)
        ->Unit(benchmark::kMicrosecond);
  }
}

const bool registered = [] {
  for (const bench::SceneSpec* spec : kScenes) {
    const std::string scene = spec->name;
    using Stage = void (*)(benchmark::State&, const bench::SceneSpec*);
    const std::pair<const char*, Stage> stages[] = {{"BM_WallCandidates/", BM_WallCandidates},
                                                    {"BM_Order/", BM_Order},
                                                    {"BM_Filter/", BM_Filter},
                                                    {"BM_Resolve/", BM_Resolve},
                                                    {"BM_Advance/", BM_Advance}};
    for (const auto& [stage, fn] : stages)
      bench::with_min(benchmark::RegisterBenchmark((stage + scene).c_str(), fn, spec))
          ->Unit(benchmark::kMicrosecond);
    const bool small = spec->n <= 2000;
    if (small) register_broad("brute", make_brute, spec);
    if (small) register_broad("grid8", make_grid, spec);
    if (spec->n <= 20000) register_broad("sweep", make_sweep, spec);
    if (spec->n <= 20000) register_broad("bands", make_bands, spec);
    register_broad("cells", make_cells, spec);
    register_broad("auto", make_auto, spec);
  }
  return true;
}();

}  // namespace
