// bench_engine: see CMakeLists.txt. The benchmarks register themselves in their files.
#include <benchmark/benchmark.h>

BENCHMARK_MAIN();
