// psim as a process: exit codes, messages on stderr, output format and the metrics file.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../scratch_folder.hpp"
#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/wait_policy.hpp"

namespace {

struct Result {
  int status;
  std::string out, err;
};

// Where a test's files go: a folder of the process's own, gone when it ends.
std::string scratch() { return test_support::scratch_folder("psim_tests").string() + "/"; }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs psim with `args`, feeding `input` on stdin, with `env` (VAR=value ...) in its environment.
Result psim(const std::string& args, const std::string& input = "", const std::string& env = "") {
  // Per-test file names: ctest runs tests in parallel.
  const std::string dir =
      scratch() + "psim_" + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const std::string in = dir + ".in", out = dir + ".out", err = dir + ".err";
  std::ofstream(in) << input;
  const std::string command =
      env + " " + std::string(PSIM_PATH) + " " + args + " < " + in + " > " + out + " 2> " + err;
  const int raw = std::system(command.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

// Why psim cannot run `engine` ("" when it can), as psim --describe says: for the mpi engine,
// psim's answer is psim-mpi's presence beside it, which this process cannot give for psim.
std::string psim_unavailable(const std::string& engine) {
  const auto described = nlohmann::json::parse(psim("--describe").out);
  for (const auto& e : described["engines"])
    if (e["name"] == engine) return e["unavailable"];
  ADD_FAILURE() << "psim --describe has no engine " << engine;
  return "";
}

std::size_t count_lines(const std::string& s) {
  std::size_t n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

TEST(Psim, PrintModeWritesEveryStepAndFinalCounts) {
  const Result r = psim("", "3\n100\n1\n4\nprint\n");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(count_lines(r.out), 3u * 5);
  EXPECT_EQ(r.out.rfind("4 2 ", 0), std::string::npos);  // final lines come last
  // Line by line: step k's lines come in particle order, steps in order, finals last.
  std::istringstream lines(r.out);
  std::string line;
  for (int k = 0; std::getline(lines, line); ++k) {
    int step = -1, i = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%d %d", &step, &i), 2) << line;
    EXPECT_EQ(step, k / 3) << "line " << k + 1 << ": " << line;
    EXPECT_EQ(i, k % 3) << "line " << k + 1 << ": " << line;
  }
  const std::string last = r.out.substr(r.out.rfind('\n', r.out.size() - 2) + 1);
  int step, i;
  double x, y, vx, vy;
  unsigned long pc, wc;
  ASSERT_EQ(std::sscanf(last.c_str(), "%d %d %lf %lf %lf %lf %lu %lu", &step, &i, &x, &y, &vx, &vy,
                        &pc, &wc),
            8)
      << last;
  EXPECT_EQ(step, 4);
  EXPECT_EQ(i, 2);
}

TEST(Psim, PerfModeWritesFirstAndLastStepWithTheSameFinalState) {
  const Result perf = psim("--engine brute", "50\n200\n1\n30\nperf\n");
  const Result print = psim("--engine brute", "50\n200\n1\n30\nprint\n");
  ASSERT_EQ(perf.status, 0);
  EXPECT_EQ(count_lines(perf.out), 100u);
  EXPECT_EQ(perf.out.substr(perf.out.find("\n30 ")), print.out.substr(print.out.find("\n30 ")));
}

TEST(Psim, MetricsFileHasEveryKey) {
  const std::string metrics = scratch() + "psim_metrics.json";
  const Result r =
      psim("--engine brute --threads 2 --metrics " + metrics, "200\n2000\n1\n20\nperf\n");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = slurp(metrics);
  for (const char* key : {"\"engine\"",
                          "\"threads\": 2",
                          "\"cpus\"",
                          "\"wall_s\"",
                          "\"stages\"",
                          "\"broad_phase_s\"",
                          "\"narrow_phase_s\"",
                          "\"order_s\"",
                          "\"filter_s\"",
                          "\"resolve_s\"",
                          "\"advance_s\"",
                          "\"counters\"",
                          "\"pair_tests\": 398000",
                          "\"candidates\"",
                          "\"pair_collisions\"",
                          "\"wall_collisions\"",
                          "\"dropped\"",
                          "\"overlaps\"",
                          "\"state_hash\"",
                          "\"energy_initial\"",
                          "\"energy_final\"",
                          "\"wait_policy\"",
                          "\"wait_policy_reason\"",
                          "\"omp_spin_count\""})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
}

TEST(Psim, MoreThreadsThanCoresWaitPassivelyWithTheSameOutput) {
  // psim executes itself again to set OMP_WAIT_POLICY: stdin must survive it, and the state too.
  const std::string metrics = scratch() + "psim_passive.json";
  const std::string scene = "50\n300\n1\n5\nprint\n";
  const Result many = psim("--threads 64 --metrics " + metrics, scene, "env -u OMP_WAIT_POLICY");
  ASSERT_EQ(many.status, 0) << many.err;
  const std::string json = slurp(metrics);
  EXPECT_NE(json.find("\"wait_policy\": \"passive\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"wait_policy_reason\": \"oversubscribed\""), std::string::npos) << json;
  EXPECT_EQ(many.out, psim("--threads 1", scene).out);
}

// psim's operator new starts blocks of 4 MiB and more a few steps past a 2 MiB boundary and
// frees them by a table of their origins (apps/huge_pages.cpp): a scene of 600,000 particles
// (4.8 MB an array) allocates and frees dozens of them, and one freed by a wrong origin would
// abort the run. Cells at T = 1 and 2 give one state.
TEST(Psim, ALargeScenesBlocksAreFreedWhereTheyCameFrom) {
  const std::string scene = "600000\n3100\n1\n2\nperf\n";
  std::string hashes[2];
  for (int threads : {1, 2}) {
    const std::string metrics = scratch() + "psim_large_" + std::to_string(threads) + ".json";
    const Result run = psim("--engine cells --speed 0.05,0.2 --threads " + std::to_string(threads) +
                                " --metrics " + metrics,
                            scene);
    ASSERT_EQ(run.status, 0) << run.err;
    EXPECT_EQ(count_lines(run.out), 2 * 600000u) << "T = " << threads;  // the first state, the last
    hashes[threads - 1] = nlohmann::json::parse(slurp(metrics))["state_hash"];
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// The CPUs the threads ran on, from the metrics' "cpus" array, without duplicates.
std::set<int> cpus_used(const std::string& json) {
  std::set<int> cpus;
  std::istringstream list(json.substr(json.find('[', json.find("\"cpus\"")) + 1));
  for (int cpu; list >> cpu;) {
    cpus.insert(cpu);
    if (list.peek() == ',') list.ignore();
  }
  return cpus;
}

// psweep pins threads (OMP_PROC_BIND=close, OMP_PLACES=cores): libgomp then binds psim's
// initial thread to one place before main, which must neither count as the only CPU nor be all
// that a re-executed psim sees. Every core must get a thread, with and without the re-execution.
TEST(Psim, PinnedThreadsUseEveryCoreWithEitherWaitPolicy) {
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  if (cores < 2) GTEST_SKIP() << "one CPU";
  for (int threads : {cores, 2 * cores}) {
    SCOPED_TRACE("T=" + std::to_string(threads));
    const std::string metrics = scratch() + "psim_pinned.json";
    const Result r = psim("--threads " + std::to_string(threads) + " --metrics " + metrics,
                          "200\n2000\n1\n50\nperf\n",
                          "env -u OMP_WAIT_POLICY OMP_PROC_BIND=close OMP_PLACES=cores");
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string json = slurp(metrics);
    EXPECT_EQ(cpus_used(json).size(), static_cast<std::size_t>(cores)) << json;
    if (threads == cores) {
      EXPECT_EQ(json.find("\"wait_policy_reason\": \"oversubscribed\""), std::string::npos) << json;
    }
  }
}

TEST(Psim, AWaitPolicyTheUserSetIsKept) {
  const std::string metrics = scratch() + "psim_active.json";
  const Result r =
      psim("--threads 64 --metrics " + metrics, "20\n300\n1\n2\nperf\n", "OMP_WAIT_POLICY=active");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string json = slurp(metrics);
  EXPECT_NE(json.find("\"wait_policy\": \"active\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"wait_policy_reason\": \"OMP_WAIT_POLICY\""), std::string::npos) << json;
}

// libgomp's own waits spin 1,000 rounds (apps/psim.cpp, choose_libgomp_spin_count), as libgomp
// itself says it read them (OMP_DISPLAY_ENV, on stderr when it starts): only a runtime linked in
// reads its environment after psim has set it, so a sanitizer's build (libgomp.so) chooses none
// and reports none. The user's GOMP_SPINCOUNT or OMP_WAIT_POLICY stands, and a passive
// re-execution takes no spin count of psim's with it. Where libgomp's own choice shows, the test
// asks only that it is not psim's (its constants differ between GCC versions).
TEST(Psim, LibgompSpinsAsPsimChose) {
  const std::string metrics = scratch() + "psim_spin.json", scene = "20\n300\n1\n2\nperf\n";
  struct Case {
    std::string env, args, displayed;  // displayed empty: libgomp's own, not psim's '1000'
    nlohmann::json reported;
  };
#ifdef PARTICLE_LIBGOMP_LINKED_IN
  const Case chosen{"", "--threads 1", "'1000'", "1000"};  // 1: no passive choice, however busy
#else
  const Case chosen{"", "--threads 1", "", nullptr};
#endif
  const std::string unset = "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT OMP_DISPLAY_ENV=verbose";
  for (Case c : {chosen, Case{" GOMP_SPINCOUNT=50", "--threads 1", "'50'", "50"},
                 Case{" OMP_WAIT_POLICY=active", "--threads 1", "", nullptr},
                 Case{"", "--threads 64", "'0'", nullptr}}) {
    c.env = unset + c.env;
    SCOPED_TRACE(c.env + " " + c.args);
    const Result r = psim(c.args + " --metrics " + metrics, scene, c.env);
    ASSERT_EQ(r.status, 0) << r.err;
    // The last display: a re-executed psim's runtime shows its own after the first one's.
    const std::size_t at = r.err.rfind("GOMP_SPINCOUNT = ");
    ASSERT_NE(at, std::string::npos) << r.err;
    const std::string shown = r.err.substr(at + 17, r.err.find('\n', at) - at - 17);
    if (c.displayed.empty())
      EXPECT_NE(shown, "'1000'") << r.err;
    else
      EXPECT_EQ(shown, c.displayed) << r.err;
    EXPECT_EQ(nlohmann::json::parse(slurp(metrics))["omp_spin_count"], c.reported);
  }
}

TEST(Psim, BadInputExitsTwoNamingLineAndField) {
  const Result r = psim("", "2\n100\n1\n10\nperf\n0 10 10 1 1\n0 20 20 1 1\n");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("<stdin>:7: i: duplicate index 0"), std::string::npos) << r.err;
}

// A run the engine must refuse (the event engine's limits, fuzz_scene's NaN at L = 4e24, r = 1)
// is refused before step 0 is written: no half output for a run that never started.
TEST(Psim, ARunTheEngineRefusesWritesNothing) {
  const std::string scene = "2\n4e24\n1\n8\nprint\n0 10 10 3 3\n1 30 30 0 4e28\n";
  const Result event = psim("--engine event", scene);
  EXPECT_EQ(event.status, 2);
  EXPECT_EQ(event.out, "");
  EXPECT_NE(event.err.find("<stdin>: r: with the event engine positions are resolved only to"),
            std::string::npos)
      << event.err;
  const Result brute = psim("--engine brute", scene);
  EXPECT_EQ(brute.status, 0) << brute.err;
  EXPECT_EQ(count_lines(brute.out), 2 * 9u);
  // the GPU and MPI engines where this machine or build cannot run them: the reason, nothing else
  for (const std::string engine : {"gpu", "mpi"})
    if (const std::string why = psim_unavailable(engine); !why.empty()) {
      const Result r =
          psim("--engine " + engine, "2\n100\n1\n4\nprint\n0 10 10 1 1\n1 50 50 0 0\n");
      EXPECT_EQ(r.status, 2) << engine;
      EXPECT_EQ(r.out, "") << engine;
      EXPECT_EQ(r.err, "psim: --engine " + engine + ": " + why + "\n");
    }
}

// Runs a shell command line; its exit status (-1 when it did not exit).
int shell(const std::string& command) {
  const int raw = std::system(command.c_str());
  return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
}

// An input that is not a regular file and never ends is read only as far as the header allows
// and refused naming the line: a device, a FIFO fed without end. Each run has a time limit (a
// psim reading without end would be stopped: 124), and the endless feed is cut at 50 MB so that
// such a psim reaches an end of input and exits 0 instead of exhausting memory.
TEST(Psim, AnInputThatNeverEndsIsRefusedNamingTheLine) {
  const std::string dir = scratch() + "psim_endless";
  const std::string err = dir + ".err", fifo = dir + ".fifo";
  const std::string psim_path = std::string("timeout 60 ") + PSIM_PATH;
  EXPECT_EQ(shell(psim_path + " /dev/zero > /dev/null 2> " + err), 2);
  EXPECT_NE(slurp(err).find("psim: /dev/zero:1: line: longer than 4096 bytes"), std::string::npos)
      << slurp(err);

  std::remove(fifo.c_str());
  ASSERT_EQ(shell("mkfifo " + fifo), 0);
  const std::string feed =
      "{ printf '3\\n100\\n1\\n10\\nperf\\n'; yes ''; } 2>/dev/null | head -c 50000000";
  EXPECT_EQ(shell("(" + feed + " > " + fifo + " &); " + psim_path + " " + fifo +
                  " > /dev/null 2> " + err),
            2);
  EXPECT_NE(slurp(err).find(".fifo:32758: input: goes on beyond 32768 bytes, the most the header "
                            "allows (8 lines of at most 4096 bytes"),
            std::string::npos)
      << slurp(err);
  std::remove(fifo.c_str());
  EXPECT_EQ(shell(feed + " | " + psim_path + " > /dev/null 2> " + err), 2);
  EXPECT_NE(slurp(err).find("psim: <stdin>:32758: input: goes on beyond"), std::string::npos)
      << slurp(err);
}

// The relay (more threads than cores, engine/src/parallel/relay.hpp) is lock-free code whose waits
// end in futex sleeps: a lost wake-up would hang a run rather than fail it. A batch of short runs
// of every shape it has (one closer per core or a single one, takers, K of 1 and 4, print mode),
// each under a time limit: a hang is a failure (124) within seconds instead of a stuck test.
TEST(Psim, TheRelayEndsEveryRunOfABatch) {
  const std::string dir = scratch() + "psim_relay_batch";
  const std::string psim_path = std::string("timeout 30 ") + PSIM_PATH;
  const int cpus = particle::available_cpus();
  cpu_set_t mask;
  ASSERT_EQ(sched_getaffinity(0, sizeof mask, &mask), 0);
  int first = 0;
  while (!CPU_ISSET(first, &mask)) ++first;
  const std::string one_cpu = "taskset -c " + std::to_string(first) + " ";
  int runs = 0;
  for (const char* mode : {"perf", "print"})
    for (int n : {40, 300}) {
      std::ofstream(dir + ".in") << n << "\n400\n1\n200\n" << mode << "\n";
      for (int threads : {cpus + 1, 2 * cpus + 3, 16})
        for (const char* k : {"1", "4"})
          for (const std::string& pin : {std::string(), one_cpu}) {
            SCOPED_TRACE(std::string(mode) + " N=" + std::to_string(n) +
                         " T=" + std::to_string(threads) + " K=" + k + " " + pin);
            const std::string run = pin + psim_path + " --engine auto --threads " +
                                    std::to_string(threads) + " --slow-factor " + k + " " + dir +
                                    ".in > " + dir + ".out";
            ASSERT_EQ(shell(run), 0);
            const std::size_t lines = count_lines(slurp(dir + ".out"));
            EXPECT_EQ(lines, static_cast<std::size_t>(n) * (mode[1] == 'r' ? 201 : 2));
            ++runs;
          }
    }
  EXPECT_EQ(runs, 48);
}

TEST(Psim, BadOptionsExitTwo) {
  EXPECT_EQ(psim("--engine warp", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--slow-factor 3", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--threads 0", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--engine grid --grid 5000", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--speed 2,1", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--speed x", "1\n10\n1\n1\nperf\n").status, 2);
  EXPECT_EQ(psim("--no-such-option").status, 2);
  EXPECT_EQ(psim("/no/such/file").status, 2);
  EXPECT_EQ(psim("--help").status, 0);
}

// Every numeric option is read as a whole decimal token within its stated bound; the message
// names the option and the form it expects (CLI11 said "Value abc not in range" and wrapped
// --seed -1 to 2^64 - 1).
TEST(Psim, OptionValuesOutsideTheirBoundsNameTheOptionAndTheForm) {
  const std::string scene = "1\n10\n1\n1\nperf\n";
  const std::pair<const char*, const char*> cases[] = {
      {"--engine warp",
       "--engine: expected one of auto, brute, grid, cells, sweep, bands, grid-unsafe, event, gpu, "
       "mpi, got \"warp\""},
      {"--threads abc", "--threads: expected an integer from 1 to 1024, got \"abc\""},
      {"--threads 1025", "--threads: expected an integer from 1 to 1024, got \"1025\""},
      {"--grid 0x10", "--grid: expected an integer from 1 to 4096, got \"0x10\""},
      {"--slow-factor 1073741824",
       "--slow-factor: expected a power of two from 1 to 2^20 = 1048576, got \"1073741824\""},
      {"--slow-factor 6", "--slow-factor: expected a power of two from 1 to 2^20"},
      {"--seed -1",
       "--seed: expected an integer from 0 to 2^64 - 1 = 18446744073709551615, got \"-1\""},
      {"--seed 18446744073709551616", "--seed: expected an integer from 0 to 2^64 - 1"},
      {"--metrics ''", "--metrics: expected a file path, got \"\""},
      {"--state-at 1 ''", "--state-at: expected a file path, got \"\""},
      {"--state-at -1 f", "--state-at: expected a time unit H, an integer from 0 to S, got \"-1\""},
  };
  for (const auto& [args, message] : cases) {
    const Result r = psim(args, scene);
    EXPECT_EQ(r.status, 2) << args;
    EXPECT_NE(r.err.find(message), std::string::npos) << args << ": " << r.err;
  }
  const Result long_token = psim("--threads " + std::string(5000, '7'), scene);
  EXPECT_EQ(long_token.status, 2);
  EXPECT_LT(long_token.err.size(), 200u) << long_token.err;
  EXPECT_NE(long_token.err.find("... (5000 bytes)"), std::string::npos) << long_token.err;
  // The bounds themselves are accepted (S = 0: K = 2^20 sub-steps a time unit are slow).
  const std::string no_steps = "1\n10\n1\n0\nperf\n";
  EXPECT_EQ(psim("--seed 18446744073709551615 --slow-factor 1048576", no_steps).status, 0);
  EXPECT_EQ(psim("--seed +0 --threads 1024", no_steps).status, 0);
}

TEST(Psim, OptionsThatShapeOnlyARandomSceneAreErrorsWithParticleLines) {
  const std::string given = "1\n10\n1\n1\nperf\n0 5 5 1 1\n";
  for (const char* option : {"--seed 4", "--speed 1,2"}) {
    const Result r = psim(option, given);
    EXPECT_EQ(r.status, 2) << option;
    const std::string name = std::string(option).substr(0, std::string(option).find(' '));
    EXPECT_NE(r.err.find(name + ": has no effect: <stdin> gives every particle's position"),
              std::string::npos)
        << r.err;
  }
  EXPECT_EQ(psim("--seed 4 --speed 1,2", "1\n10\n1\n1\nperf\n").status, 0);  // a random scene
}

TEST(Psim, ThreadsAreBoundedByOpenMPsThreadLimit) {
  const Result r = psim("--threads 8", "1\n10\n1\n1\nperf\n", "OMP_THREAD_LIMIT=4");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--threads: expected an integer from 1 to 4, got \"8\""), std::string::npos)
      << r.err;
  EXPECT_EQ(psim("--threads 4", "1\n10\n1\n1\nperf\n", "OMP_THREAD_LIMIT=4").status, 0);
}

TEST(Psim, ThreadsFromTheEnvironmentAreBoundedToo) {
  const Result r = psim("", "1\n10\n1\n1\nperf\n", "OMP_NUM_THREADS=5000");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("OMP_NUM_THREADS: expected at most 1024 threads, got 5000"),
            std::string::npos)
      << r.err;
}

// Overlapping particles in an input file run (exit 0) with a warning: how many pairs and the first
// in (i, j) order, also where the squared distances underflow (L = 1e-200).
TEST(Psim, OverlappingParticlesInAnInputFileAreAWarning) {
  // Overlapping pairs (2, 3) and (0, 3), found in that order; (0, 3) is the first.
  const std::string particles = "0 10 10 0 0\n1 50 50 1 0\n2 13 10 0 0\n3 11.5 10 0 0\n";
  const Result r = psim("", "4\n100\n1\n2\nperf\n" + particles);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("psim: warning: <stdin>: 2 pairs of particles overlap (centres closer "
                       "than 2r = 2), the first 0 and 3 at distance 1.5"),
            std::string::npos)
      << r.err;
  const Result tiny = psim("",
                           "2\n1e-200\n1e-201\n2\nperf\n0 3e-201 3e-201 0 0\n"
                           "1 4.5e-201 3e-201 0 0\n");
  EXPECT_EQ(tiny.status, 0) << tiny.err;
  EXPECT_NE(tiny.err.find("1 pair of particles overlaps (centres closer than 2r = 2e-201), the "
                          "first 0 and 1 at distance 1.5e-201"),
            std::string::npos)
      << tiny.err;
  // Touching is not overlapping; a random scene never overlaps.
  EXPECT_EQ(psim("", "2\n100\n1\n2\nperf\n0 10 10 0 0\n1 12 10 0 0\n").err, "");
  EXPECT_EQ(psim("", "500\n100\n1\n2\nperf\n").err, "");
}

// --state-at H FILE writes the step-H lines of print mode, also in perf mode, for any engine.
TEST(Psim, StateAtWritesTheStateAtTimeUnitH) {
  const std::string head_on = "2\n100\n1\n4\nperf\n0 40 50 5 0\n1 60 50 -5 0\n";
  const std::string file = scratch() + "psim_state_at.txt";
  for (const char* engine : {"brute", "event"}) {
    std::remove(file.c_str());
    const Result r = psim(std::string("--engine ") + engine + " --state-at 2 " + file, head_on);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(slurp(file),
              "2 0 48.00000000 50.00000000 -5.00000000 0.00000000\n"
              "2 1 52.00000000 50.00000000 5.00000000 0.00000000\n")
        << engine;
  }
  ASSERT_EQ(psim("--state-at 0 " + file, head_on).status, 0);
  EXPECT_EQ(slurp(file).substr(0, 2), "0 ");
  ASSERT_EQ(psim("--state-at 4 " + file, head_on).status, 0);
  EXPECT_EQ(slurp(file).substr(0, 2), "4 ");
  const Result late = psim("--state-at 5 " + file, head_on);
  EXPECT_EQ(late.status, 2);
  EXPECT_NE(late.err.find("--state-at: H must be a time unit in [0, S = 4], got 5"),
            std::string::npos)
      << late.err;
  EXPECT_EQ(psim("--state-at 1 /no/such/dir/f", head_on).status, 2);
  EXPECT_EQ(psim("--state-at x " + file, head_on).status, 2);
}

// The scene psweep gives an external program: the random scene's particles, every value read back
// as the same double, so the written scene runs exactly as the random one (the same output).
TEST(Psim, WriteSceneWritesTheParticlesARunReads) {
  const std::string file = scratch() + "psim_write_scene.in";
  std::remove(file.c_str());
  const std::string header = "20\n1000\n1\n30\nprint\n";
  const Result written = psim("--seed 11 --write-scene " + file, header);
  ASSERT_EQ(written.status, 0) << written.err;
  EXPECT_EQ(written.out, "");  // nothing is run
  const std::string scene = slurp(file);
  EXPECT_EQ(scene.substr(0, header.size()), header);
  EXPECT_EQ(count_lines(scene), 25u);
  const Result random = psim("--seed 11", header);
  const Result explicit_scene = psim("", scene);
  ASSERT_EQ(explicit_scene.status, 0) << explicit_scene.err;
  EXPECT_EQ(explicit_scene.out, random.out);
  EXPECT_EQ(psim("--seed 11 --write-scene " + file + " --metrics m.json", header).status, 2);
  EXPECT_EQ(psim("--write-scene " + file + " --state-at 1 s.txt", header).status, 2);
  EXPECT_EQ(psim("--write-scene /no/such/dir/f", header).status, 2);
}

TEST(Psim, DescribePrintsTheDeclaration) {
  const Result r = psim("--describe");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // Where psim can run the mpi engine is psim's to say (psim-mpi beside it), not this process's.
  auto same = nlohmann::json::parse(particle::describe_json());
  for (std::size_t i = 0; i < j["engines"].size(); ++i)
    if (j["engines"][i]["name"] == "mpi")
      same["engines"][i]["unavailable"] = j["engines"][i]["unavailable"];
  EXPECT_EQ(j, same);
  ASSERT_EQ(j["engines"].size(), particle::engines().size());
  for (std::size_t i = 0; i < particle::engines().size(); ++i) {
    const particle::EngineInfo& e = particle::engines()[i];
    EXPECT_EQ(j["engines"][i]["name"], std::string(e.name));
    EXPECT_EQ(j["engines"][i]["uses"].size(), static_cast<std::size_t>(std::popcount(e.uses)));
  }
  const auto& grid = j["engines"][2];  // psim --list-engines order
  EXPECT_EQ(grid["name"], "grid");
  EXPECT_EQ(grid["uses"], nlohmann::json({"T", "G", "slow_factor", "wall_stop", "overlap"}));
  const auto& brute = j["engines"][1];
  EXPECT_EQ(brute["uses"], nlohmann::json({"T", "slow_factor", "wall_stop", "overlap"}));
  EXPECT_TRUE(brute["reference"].get<bool>());
  EXPECT_EQ(brute["growth"], "N^2");  // the cost model's fact: every pair each sub-step
  EXPECT_EQ(grid["growth"], "N");
  for (const auto& e : j["engines"])  // the accuracy reference: event alone
    EXPECT_EQ(e["continuous_time"].get<bool>(), e["name"] == "event") << e["name"];
  EXPECT_EQ(j["metrics"][0]["key"], "broad_phase_s");
  EXPECT_EQ(j["metrics"][0]["section"], "stages");
  EXPECT_EQ(j["metrics"][6]["key"], "pair_tests");
  EXPECT_EQ(j["metrics"][6]["kind"], "counter");
}

// --header: the header as a run reads it (analysis/common/trajectory.py asks psim instead of
// parsing).
// The mpi engine is psim-mpi's, which psim finds beside its own executable: a copy of psim alone
// (the working folder psim-mpi's) says so in --describe and refuses the engine with that reason,
// writing nothing. psim-mpi answers for itself, and runs brute's bits for a single process.
TEST(Psim, TheMpiEngineIsPsimMpiBesidePsim) {
#ifndef WITH_MPI
  GTEST_SKIP() << "a build without MPI: no psim-mpi";
#endif
  EXPECT_EQ(psim_unavailable("mpi"), "");
  const std::filesystem::path alone = scratch() + "psim_alone";
  std::filesystem::create_directories(alone);
  std::filesystem::copy_file(PSIM_PATH, alone / "psim",
                             std::filesystem::copy_options::overwrite_existing);
  const std::string scene = "2\n100\n1\n4\nprint\n0 10 10 1 1\n1 50 50 0 0\n";
  const std::string command = "cd " + std::filesystem::path(PSIM_PATH).parent_path().string() +
                              " && " + (alone / "psim").string();
  const auto run = [&](const std::string& args) {
    const std::string out = alone / "out", err = alone / "err", in = alone / "in";
    std::ofstream(in) << scene;
    const int raw =
        std::system((command + " " + args + " < " + in + " > " + out + " 2> " + err).c_str());
    return Result{WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
  };
  const std::string why = "its program " + (alone / "psim-mpi").string() +
                          " is missing (psim runs the engine in psim-mpi beside it: make tools "
                          "builds both; a copy of psim needs psim-mpi beside it)";
  const auto described = nlohmann::json::parse(run("--describe").out);
  bool said = false;
  for (const auto& e : described["engines"])
    if (e["name"] == "mpi") said = e["unavailable"] == why;
  EXPECT_TRUE(said) << described.dump();
  const Result refused = run("--engine mpi");
  EXPECT_EQ(refused.status, 2);
  EXPECT_EQ(refused.out, "");
  EXPECT_EQ(refused.err, "psim: --engine mpi: " + why + "\n");
  const Result mpi = psim("--engine mpi", scene), brute = psim("--engine brute", scene);
  EXPECT_EQ(mpi.status, 0) << mpi.err;
  EXPECT_EQ(mpi.out, brute.out);
}

TEST(Psim, HeaderPrintsTheHeaderARunReads) {
  const Result r = psim("--header", "1000\n2e4\n1\n0\nprint\n");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out),
            nlohmann::json::parse(R"({"N": 1000, "L": 20000, "r": 1, "S": 0, "mode": "print"})"));
  const std::string bad = "1000\n2e4\n-1\n0\nprint\n";
  const Result header = psim("--header", bad), run = psim("", bad);
  EXPECT_EQ(header.status, 2);
  EXPECT_EQ(header.err, run.err);  // the same rule, the same message
  EXPECT_NE(header.err.find("<stdin>:3: r"), std::string::npos) << header.err;
}

// Every declared metric is in --metrics, in its section, with its declared type: the JSON is
// written from the declaration, so a new metric cannot be forgotten there.
TEST(Psim, MetricsFollowTheDeclaration) {
  const std::string metrics = scratch() + "psim_declared.json";
  const Result r = psim("--engine grid --threads 2 --metrics " + metrics, "50\n500\n1\n10\nperf\n");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(slurp(metrics));
  for (const particle::MetricInfo& m : particle::metrics()) {
    const std::string section(particle::section(m.kind));
    if (m.kind == particle::MetricKind::rank) {
      // the ranks' traffic does not apply to a run in one process: left out, never a 0
      EXPECT_FALSE(j.contains(section)) << m.key;
      continue;
    }
    const auto& obj = section.empty() ? j : j[section];
    ASSERT_TRUE(obj.contains(std::string(m.key))) << m.key;
    const auto& v = obj[std::string(m.key)];
    switch (m.type) {
      case particle::MetricValue::Type::real:
        EXPECT_TRUE(v.is_number()) << m.key;
        break;
      case particle::MetricValue::Type::count:
        EXPECT_TRUE(v.is_number_unsigned()) << m.key;
        break;
      case particle::MetricValue::Type::flag:
        EXPECT_TRUE(v.is_boolean()) << m.key;
        break;
    }
  }
  // elastic collisions conserve kinetic energy to rounding
  EXPECT_NEAR(j["energy_final"].get<double>(), j["energy_initial"].get<double>(),
              1e-9 * j["energy_initial"].get<double>());
  EXPECT_GT(j["energy_initial"].get<double>(), 0);
}

// psim started with `args` on the scene file `input`, stdout to `out`; signalled with `signal` once
// it has written step 0 (its handlers are in place by then). Returns the exit status, -1 when it
// died of the signal or ran on for 20 s after it.
int interrupted_psim(const std::vector<std::string>& args, const std::string& input,
                     const std::string& out, int signal) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::freopen(input.c_str(), "r", stdin);
    std::freopen(out.c_str(), "w", stdout);
    setenv("OMP_WAIT_POLICY", "passive", 1);  // no re-execution: the pid stays psim's
    std::vector<char*> argv{const_cast<char*>(PSIM_PATH)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(PSIM_PATH, argv.data());
    _exit(127);
  }
  const auto waited = [&](int& raw) { return waitpid(pid, &raw, WNOHANG) == pid; };
  int raw = 0;
  for (int ms = 0; ms < 20000 && slurp(out).find("\n0 49 ") == std::string::npos; ms += 10) {
    if (waited(raw)) return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // into the simulation
  kill(pid, signal);
  for (int ms = 0; ms < 20000; ms += 10) {
    if (waited(raw)) return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &raw, 0);
  return -1;
}

// SIGINT/SIGTERM stop the run at the next sub-step boundary (event: the next event): the state
// reached on stdout, labelled with its time, complete metrics with interrupted and time_reached,
// exit 128 + signal. Without the handler psim died of the signal and left an empty metrics file.
TEST(Psim, ASignalStopsTheRunWithTheStateReachedAndCompleteMetrics) {
  const std::string dir = scratch() + "psim_interrupt";
  const std::string input = dir + ".in", out = dir + ".out", metrics = dir + ".json";
  std::ofstream(input) << "50\n2000\n1\n1000000000000\nperf\n";  // S = 1e12: never ends alone
  std::ofstream(dir + "_event.in") << "50\n2000\n1\n100000000\nperf\n";  // within event's budget
  struct Case {
    std::vector<std::string> options;
    std::string input;
    int signal, slow_factor;
  };
  const Case cases[] = {
      {{"--engine", "brute", "--threads", "1", "--state-at", "900000000000", dir + ".state"},
       input,
       SIGINT,
       1},
      {{"--engine", "sweep", "--threads", "2", "--slow-factor", "4"}, input, SIGTERM, 4},
      // More threads than cores: the relay (engine/src/parallel/relay.hpp).
      {{"--engine", "auto", "--threads", std::to_string(particle::available_cpus() + 1),
        "--slow-factor", "2"},
       input,
       SIGINT,
       2},
      {{"--engine", "event"}, dir + "_event.in", SIGINT, 1},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.options[1]);
    std::remove(metrics.c_str());
    std::vector<std::string> args = c.options;
    args.insert(args.end(), {"--metrics", metrics, c.input});
    ASSERT_EQ(interrupted_psim(args, c.input, out, c.signal), 128 + c.signal);
    const auto j = nlohmann::json::parse(slurp(metrics));  // whole JSON, or this throws
    EXPECT_TRUE(j["interrupted"].get<bool>());
    const double reached = j["time_reached"].get<double>();
    EXPECT_GT(reached, 0);
    EXPECT_LT(reached, 1e8);
    if (c.options[1] != "event") {  // a sub-step boundary: a whole number of 1/K
      EXPECT_EQ(std::floor(reached * c.slow_factor), reached * c.slow_factor);
    }
    EXPECT_EQ(j["energy_drift"].get<double>(), j["energy_drift"].get<double>());  // not NaN
    EXPECT_FALSE(std::ifstream(dir + ".state").good()) << "time unit H was never reached";
    // The final lines (with the counts) are the state at time_reached, labelled with it.
    const std::string text = slurp(out);
    EXPECT_EQ(count_lines(text), 100u);
    const std::string last = text.substr(text.rfind('\n', text.size() - 2) + 1);
    EXPECT_EQ(last.substr(0, last.find(' ')), particle::time_label(reached)) << last;
    EXPECT_EQ(std::count(last.begin(), last.end(), ' '), 7) << last;
    // A discrete engine at K = 1 stopped at a whole time unit: the same state as a run to it.
    if (c.slow_factor == 1 && c.options[1] != "event") {
      const Result whole = psim("--engine brute --threads 1",
                                "50\n2000\n1\n" + particle::time_label(reached) + "\nperf\n");
      EXPECT_EQ(text, whole.out);
    }
  }
}

// Files appear whole or not at all: written under a temporary name and renamed when complete.
TEST(Psim, AFailedRunLeavesNoMetricsFile) {
  const std::string metrics = scratch() + "psim_failed.json";
  std::remove(metrics.c_str());
  const Result r =
      psim("--metrics " + metrics + " --state-at 5 " + metrics + ".state", "2\n100\n1\n4\nperf\n");
  EXPECT_EQ(r.status, 2) << r.err;
  for (const auto& entry : std::filesystem::directory_iterator(scratch()))
    EXPECT_EQ(entry.path().filename().string().find("psim_failed"), std::string::npos)
        << entry.path() << ": a file of a run that never ran";
}

TEST(Psim, ListsEngines) {
  const Result r = psim("--list-engines");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("brute\n"), std::string::npos);
}

}  // namespace

// psim check reads its command line with CLI11 and the lab's wording, as psim does.
TEST(Psim, CheckParsesItsCommandLineAsPsimDoes) {
  const std::string scene = std::string(SCENES_DIR) + "/head_on.in";
  const std::string output = scratch() + "psim_check_head_on.out";
  ASSERT_EQ(std::system((std::string(PSIM_PATH) + " " + scene + " > " + output).c_str()), 0);
  const std::string json = scratch() + "psim_check.json";
  const Result ok = psim("check " + scene + " " + output + " --slow-factor=1 --json=" + json);
  EXPECT_EQ(ok.status, 0) << ok.err;
  EXPECT_NE(ok.out.find("verdict: exact"), std::string::npos) << ok.out;
  EXPECT_NE(slurp(json).find("\"verdict\": \"exact\""), std::string::npos);
  const Result twice = psim("check " + scene + " " + output + " --json a.json --json b.json");
  EXPECT_EQ(twice.status, 2);
  EXPECT_NE(twice.err.find("psim check: --json: given 2 times; give it once"), std::string::npos)
      << twice.err;
  const Result missing = psim("check " + scene);
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("psim check: OUTPUT is missing"), std::string::npos) << missing.err;
  const Result extra = psim("check " + scene + " " + output + " third");
  EXPECT_EQ(extra.status, 2);
  EXPECT_NE(extra.err.find("not an option or argument here: third"), std::string::npos);
  const Result k = psim("check " + scene + " " + output + " --slow-factor 3");
  EXPECT_EQ(k.status, 2);
  EXPECT_NE(k.err.find("--slow-factor: expected a power of two"), std::string::npos) << k.err;
  EXPECT_EQ(psim("check --help").status, 0);
}
