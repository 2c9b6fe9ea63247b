// psim --engine mpi as processes under mpiexec (issue 43): what psim writes is brute's, byte for
// byte, in print mode and in the metrics; rank 0 alone writes; an error before the run ends every
// rank with it; a signal stops every rank after the same sub-step. Skipped, with the reason, in a
// build without MPI.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../scratch_folder.hpp"
#include "particle/io.hpp"

namespace {

// What every launch here needs: root may launch (this lab's machines run as root), more ranks
// than cores, and passive OpenMP waits (ranks and threads share the cores).
const char* const kEnvironment =
    "OMP_WAIT_POLICY=passive OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 "
    "OMPI_MCA_rmaps_base_oversubscribe=1";

struct Result {
  int status;
  std::string out, err;
};

std::string scratch() { return test_support::scratch_folder("psim_mpi_tests").string() + "/"; }

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// psim with `args` on `ranks` processes (1: no launcher), `input` on stdin, within 120 s.
Result psim(int ranks, const std::string& args, const std::string& input = "") {
  const std::string dir =
      scratch() + ::testing::UnitTest::GetInstance()->current_test_info()->name();
  const std::string in = dir + ".in", out = dir + ".out", err = dir + ".err";
  std::ofstream(in) << input;
  const std::string launch =
      ranks == 1 ? "" : std::string(MPIEXEC) + " -n " + std::to_string(ranks) + " ";
  const std::string command = std::string("env ") + kEnvironment + " timeout 120 " + launch +
                              PSIM_PATH + " " + args + " < " + in + " > " + out + " 2> " + err;
  const int raw = std::system(command.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out), slurp(err)};
}

// Why psim cannot run the mpi engine ("" when it can), as psim --describe says (psim-mpi beside
// it, which this process cannot tell for psim).
std::string psim_unavailable() {
  const auto described = nlohmann::json::parse(psim(1, "--describe").out);
  for (const auto& e : described["engines"])
    if (e["name"] == "mpi") return e["unavailable"];
  return "psim --describe has no engine mpi";
}

class PsimMpi : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const std::string why = psim_unavailable(); !why.empty())
      GTEST_SKIP() << "the mpi engine: " << why;
  }
};

// The metrics that must be brute's: the state hash, the counters but pair_tests, the physics.
nlohmann::json brutes_part(const std::string& metrics_file) {
  nlohmann::json j = nlohmann::json::parse(slurp(metrics_file));
  j["counters"].erase("pair_tests");  // each broad phase prunes and builds its own way
  j["counters"].erase("broad_phase_builds");
  return {{"state_hash", j["state_hash"]},     {"counters", j["counters"]},
          {"energy_final", j["energy_final"]}, {"max_overlap", j["max_overlap"]},
          {"wall_impulse", j["wall_impulse"]}, {"time_reached", j["time_reached"]}};
}

// The ranks' traffic of a run on `ranks` processes (psim --metrics "ranks"): every rank runs
// every filter round; one rank alone holds no halo and sends nothing; more send (the counts and
// sums at least) and, on a scene spread over the box (`spread`), hold copies; a largest is never
// below its mean, nor the waiting above the communicating.
void expect_rank_traffic(const nlohmann::json& r, int ranks, bool spread) {
  ASSERT_TRUE(r.is_object());
  EXPECT_EQ(r["ranks"], ranks);
  EXPECT_EQ(r["nodes"], 1);  // every rank here (make test-slurm runs them across nodes)
  EXPECT_GT(r["filter_rounds"].get<double>(), 0);
  if (ranks == 1) {
    EXPECT_EQ(r["halo_particles_max"], 0);
    EXPECT_EQ(r["bytes_sent_max"], 0);
  } else {
    if (spread) {
      EXPECT_GT(r["halo_particles_mean"].get<double>(), 0);
    }
    EXPECT_GT(r["bytes_sent_mean"].get<double>(), 0);
  }
  for (const char* what : {"halo_particles", "bytes_sent", "comm_s", "wait_s"})
    EXPECT_GE(r[std::string(what) + "_max"].get<double>(),
              r[std::string(what) + "_mean"].get<double>())
        << what;
  EXPECT_GE(r["comm_s_mean"].get<double>(), r["wait_s_mean"].get<double>());
  EXPECT_GT(r["comm_s_max"].get<double>(), 0);
}

// Print mode: every time unit of every particle, byte for byte, at P = 1 (no launcher), 2, 3
// and 8 ranks, T = 1 or 2; a scene from a file, a random one from stdin, one at K = 2 with the
// other wall-stop reading.
TEST_F(PsimMpi, PrintModeWritesBrutesBytes) {
  const std::string metrics = scratch() + "print.json";
  const std::string cradle = std::string(SCENES_DIR) + "/cradle.in";
  struct Scene {
    std::string args, input;
  };
  const Scene scenes[] = {
      {cradle, ""},
      {"--seed 11", "300\n3000\n1\n20\nprint\n"},
      {"--seed 42 --slow-factor 2 --wall-stop whole-motion", "300\n150\n2\n10\nprint\n"}};
  const int layouts[][2] = {{1, 2}, {2, 1}, {3, 2}, {8, 1}};  // P, T
  for (const Scene& scene : scenes) {
    const Result brute =
        psim(1, "--engine brute --threads 1 --metrics " + metrics + " " + scene.args, scene.input);
    ASSERT_EQ(brute.status, 0) << brute.err;
    const nlohmann::json want = brutes_part(metrics);
    for (const auto& [ranks, threads] : layouts) {
      SCOPED_TRACE(scene.args + " P=" + std::to_string(ranks) + " T=" + std::to_string(threads));
      const Result mpi = psim(ranks,
                              "--engine mpi --threads " + std::to_string(threads) + " --metrics " +
                                  metrics + " " + scene.args,
                              scene.input);
      ASSERT_EQ(mpi.status, 0) << mpi.err;
      EXPECT_EQ(mpi.out, brute.out);
      EXPECT_EQ(brutes_part(metrics), want);
      const nlohmann::json j = nlohmann::json::parse(slurp(metrics));
      EXPECT_EQ(j["engine"], "mpi");
      expect_rank_traffic(j["ranks"], ranks, !scene.input.empty());  // the random scenes
    }
  }
}

// Perf mode with --state-at H: the state at H and the final one are brute's at P = 2 and 3. At
// P > 1 rank 0 holds the run's arrays only while it writes (engine/src/mpi/engine.cpp): the
// state at H is gathered into arrays allocated again, and freed after.
TEST_F(PsimMpi, StateAtATimeUnitIsBrutes) {
  const std::string input = "400\n300\n1\n12\nperf\n", args = " --seed 8 --state-at 5 ";
  const Result brute =
      psim(1, "--engine brute --threads 1" + args + scratch() + "brute.state", input);
  ASSERT_EQ(brute.status, 0) << brute.err;
  const std::string state = slurp(scratch() + "brute.state");
  ASSERT_EQ(std::count(state.begin(), state.end(), '\n'), 400);  // a line per particle
  ASSERT_EQ(state.rfind("5 0 ", 0), 0u);                         // at H = 5, particle 0 first
  for (int ranks : {2, 3}) {
    SCOPED_TRACE("P=" + std::to_string(ranks));
    const Result mpi =
        psim(ranks, "--engine mpi --threads 1" + args + scratch() + "mpi.state", input);
    ASSERT_EQ(mpi.status, 0) << mpi.err;
    EXPECT_EQ(mpi.out, brute.out);
    EXPECT_EQ(slurp(scratch() + "mpi.state"), slurp(scratch() + "brute.state"));
  }
}

// Rank 0 decides before the run (bad input, an option it refuses, --write-scene) and the others
// end with its status, writing nothing: one message, no hang.
TEST_F(PsimMpi, WhatEndsTheLeaderBeforeTheRunEndsEveryRank) {
  const Result bad = psim(3, "--engine mpi", "2\n100\n1\n10\nperf\n0 10 10 1 1\n0 20 20 1 1\n");
  EXPECT_EQ(bad.status, 2);
  EXPECT_EQ(bad.out, "");
  // The message once, from rank 0 (the launcher adds its own lines on a non-zero exit).
  EXPECT_EQ(bad.err.find("psim: "), 0u) << bad.err;
  EXPECT_EQ(bad.err.find("psim: ", 1), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("psim: <stdin>:7: i: duplicate index 0\n"), std::string::npos) << bad.err;
  const Result late = psim(3, "--engine mpi --state-at 9 " + scratch() + "late.state",
                           "2\n100\n1\n4\nperf\n0 10 10 1 1\n1 20 20 1 1\n");
  EXPECT_EQ(late.status, 2);
  EXPECT_NE(late.err.find("--state-at: H must be a time unit in [0, S = 4], got 9"),
            std::string::npos)
      << late.err;
  const std::string written = scratch() + "written.in";
  const Result scene = psim(3, "--engine mpi --write-scene " + written, "5\n100\n1\n4\nperf\n");
  EXPECT_EQ(scene.status, 0) << scene.err;
  const std::string lines = slurp(written);
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), 10);
}

// SIGTERM to the launcher, which passes it to every rank: each asks the others at the start of a
// sub-step, so all stop after the same one; rank 0 writes the state reached, which is brute's
// run to that time.
TEST_F(PsimMpi, ASignalStopsEveryRankAfterTheSameSubStep) {
  const std::string dir = scratch() + "interrupt";
  const std::string input = dir + ".in", out = dir + ".out", metrics = dir + ".json";
  std::ofstream(input) << "50\n2000\n1\n1000000000000\nperf\n";  // S = 1e12: never ends alone
  const pid_t pid = fork();
  if (pid == 0) {
    std::freopen(out.c_str(), "w", stdout);
    std::freopen((dir + ".err").c_str(), "w", stderr);
    std::istringstream environment(kEnvironment);
    for (std::string pair; environment >> pair;) putenv(strdup(pair.c_str()));
    execl(MPIEXEC, MPIEXEC, "-n", "3", PSIM_PATH, "--engine", "mpi", "--threads", "1", "--metrics",
          metrics.c_str(), input.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  for (int ms = 0; ms < 30000 && slurp(out).find("\n0 49 ") == std::string::npos; ms += 10)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // into the simulation
  kill(pid, SIGTERM);
  int raw = 0;
  for (int ms = 0; ms < 30000 && waitpid(pid, &raw, WNOHANG) != pid; ms += 10)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (waitpid(pid, &raw, WNOHANG) == 0) {
    kill(pid, SIGKILL);
    waitpid(pid, &raw, 0);
    FAIL() << "the launcher did not end within 30 s of SIGTERM: " << slurp(dir + ".err");
  }
  const auto j = nlohmann::json::parse(slurp(metrics));  // whole JSON, or this throws
  EXPECT_TRUE(j["interrupted"].get<bool>());
  const double reached = j["time_reached"].get<double>();
  ASSERT_GT(reached, 0);
  const std::string text = slurp(out);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 100);
  const Result whole = psim(1, "--engine brute --threads 1",
                            "50\n2000\n1\n" + particle::time_label(reached) + "\nperf\n");
  EXPECT_EQ(text, whole.out);
}

}  // namespace
