// The pair-test kernel: test_row (brute's rows, long and contiguous) and test_span (a broad
// phase's copy; short spans take the masked 8-lane path). Items are pairs, so the rate reads as
// pairs per second; time per pair = 1 / rate.
#include <numeric>

#include "bench_scene.hpp"
#include "step/narrow_phase.hpp"

namespace {

using namespace particle::detail;

// All pairs of the default scene's first state, row by row as brute does (one thread).
void BM_TestRowAllPairs(benchmark::State& st) {
  const World& w = bench::state_of(bench::kDefault).w;
  const auto n = static_cast<std::uint32_t>(w.n);
  ThreadScratch out;
  for (auto _ : st) {
    out.clear_candidates();
    for (std::uint32_t i = 0; i + 1 < n; ++i) test_row(w, i, i + 1, n, out);
    benchmark::DoNotOptimize(out.candidates.data());
  }
  st.SetItemsProcessed(st.iterations() * (std::int64_t(n) * (n - 1) / 2));
}
BENCHMARK(BM_TestRowAllPairs)->Apply([](auto* b) { bench::with_min(b); });

// One row of a given length, repeated over the default scene's particles.
void BM_TestRow(benchmark::State& st) {
  const World& w = bench::state_of(bench::kDefault).w;
  const auto len = static_cast<std::uint32_t>(st.range(0));
  ThreadScratch out;
  std::uint32_t i = 0;
  for (auto _ : st) {
    out.clear_candidates();
    for (int rep = 0; rep < 64; ++rep, i = (i + 1) % 64) test_row(w, i, 64, 64 + len, out);
    benchmark::DoNotOptimize(out.candidates.data());
  }
  st.SetItemsProcessed(st.iterations() * 64 * len);
}
BENCHMARK(BM_TestRow)->Arg(8)->Arg(64)->Arg(900)->Apply([](auto* b) { bench::with_min(b); });

// test_span over a copy (here the crowd's own arrays with ids 0..N-1), span lengths as in cells
// (a few particles) and sweep (hundreds).
void BM_TestSpan(benchmark::State& st) {
  const World& w = bench::state_of(bench::kCrowd).w;
  static const std::vector<std::uint32_t> ids = [&] {
    std::vector<std::uint32_t> v(w.n);
    std::iota(v.begin(), v.end(), 0u);
    return v;
  }();
  const SpanArrays a{w.x, w.y, w.ux, w.uy, ids.data()};
  const auto len = static_cast<std::uint32_t>(st.range(0));
  ThreadScratch out;
  for (auto _ : st) {
    out.clear_candidates();
    for (std::uint32_t i = 0; i < 1024; ++i) {
      const RowParticle p{w.x[i], w.y[i], w.ux[i], w.uy[i], i};
      test_span(p, a, 2048 + i * 8, 2048 + i * 8 + len, w.s2, out);
    }
    benchmark::DoNotOptimize(out.candidates.data());
  }
  st.SetItemsProcessed(st.iterations() * 1024 * len);
  st.counters["span_time"] =
      benchmark::Counter(static_cast<double>(st.iterations()) * 1024,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_TestSpan)->Arg(3)->Arg(8)->Arg(24)->Arg(200)->Apply([](auto* b) {
  bench::with_min(b);
});

}  // namespace
