// Input and output: `%.8f` of the default scene's coordinates and velocities by format_fixed8,
// by fmt (the formatter before it) and by snprintf; whole state lines through StateWriter; and
// the particle lines parsed back by read_scene. Items are doubles or lines.
#include <fmt/format.h>

#include <cstdio>
#include <sstream>

#include "bench_scene.hpp"
#include "io/fixed8.hpp"

namespace {

// The default scene's state as the 4N doubles a state line prints.
const std::vector<double>& printed_values() {
  static const std::vector<double> values = [] {
    const particle::Particles& p = bench::state_of(bench::kDefault).scene.particles;
    std::vector<double> v;
    for (const auto* a : {&p.x, &p.y, &p.vx, &p.vy}) v.insert(v.end(), a->begin(), a->end());
    return v;
  }();
  return values;
}

void BM_Fixed8(benchmark::State& st) {
  const auto& values = printed_values();
  char text[particle::kMaxFixed8Chars];
  for (auto _ : st)
    for (double v : values) {
      benchmark::DoNotOptimize(particle::detail::format_fixed8(text, v));
      benchmark::ClobberMemory();
    }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(values.size()));
}

void BM_FmtFixed(benchmark::State& st) {
  const auto& values = printed_values();
  char text[particle::kMaxFixed8Chars];
  for (auto _ : st)
    for (double v : values) {
      benchmark::DoNotOptimize(fmt::format_to(text, "{:.8f}", v));
      benchmark::ClobberMemory();
    }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(values.size()));
}

void BM_Snprintf(benchmark::State& st) {
  const auto& values = printed_values();
  char text[particle::kMaxFixed8Chars];
  for (auto _ : st)
    for (double v : values) {
      benchmark::DoNotOptimize(std::snprintf(text, sizeof text, "%.8f", v));
      benchmark::ClobberMemory();
    }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(values.size()));
}

// One print-mode time unit of the default scene (1000 lines) into /dev/null, serially.
void BM_WriteState(benchmark::State& st) {
  const particle::Particles& p = bench::state_of(bench::kDefault).scene.particles;
  std::FILE* null = std::fopen("/dev/null", "w");
  {
    particle::StateWriter writer(null, 1);
    for (auto _ : st) writer.write(7, p);
  }
  std::fclose(null);
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(p.size()));
}

// read_scene on the default scene with its particle lines (as psim would print them).
void BM_ReadScene(benchmark::State& st) {
  const particle::Particles& p = bench::state_of(bench::kDefault).scene.particles;
  std::string text = "1000\n20000\n1\n1000\nperf\n";
  for (std::size_t i = 0; i < p.size(); ++i)
    text += fmt::format("{} {:.8f} {:.8f} {:.8f} {:.8f}\n", i, p.x[i], p.y[i], p.vx[i], p.vy[i]);
  for (auto _ : st) {
    std::istringstream in(text);
    benchmark::DoNotOptimize(particle::read_scene(in, "bench", {}));
  }
  st.SetItemsProcessed(st.iterations() * static_cast<std::int64_t>(p.size()));
}

const int registered = [] {
  bench::with_min(benchmark::RegisterBenchmark("io/fixed8", BM_Fixed8));
  bench::with_min(benchmark::RegisterBenchmark("io/fmt_fixed", BM_FmtFixed));
  bench::with_min(benchmark::RegisterBenchmark("io/snprintf", BM_Snprintf));
  bench::with_min(benchmark::RegisterBenchmark("io/write_state", BM_WriteState));
  bench::with_min(benchmark::RegisterBenchmark("io/read_scene", BM_ReadScene));
  return 0;
}();

}  // namespace
