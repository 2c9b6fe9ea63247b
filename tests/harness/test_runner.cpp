// The runner against small shell scripts: exit codes, stderr, signals, timeouts that kill the whole
// process group, the environment, and perf counters where the kernel allows them.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "run/runner.hpp"

using namespace psweep;

namespace {

ChildResult sh(const std::string& script, double timeout_s = 10,
               const std::vector<std::string>& env = {"PATH=/usr/bin:/bin"},
               const CounterAvailability* counters = nullptr) {
  return run_child({"/bin/sh", "-c", script}, env, timeout_s, counters);
}

// The state letter of /proc/PID/stat ('Z' = zombie), or 0 when the process does not exist.
char process_state(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  std::getline(in, stat);
  auto paren = stat.rfind(')');
  return paren == std::string::npos || paren + 2 >= stat.size() ? 0 : stat[paren + 2];
}

}  // namespace

TEST(Runner, ExitCodeAndStderrTail) {
  auto r = sh("echo to-stdout; echo first >&2; echo last >&2; exit 3");
  EXPECT_EQ(r.outcome, Outcome::exited);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.stderr_tail, "first\nlast\n");  // stdout went to /dev/null
  EXPECT_GT(r.process_s, 0);
}

TEST(Runner, KeepsOnlyTheTailOfLongStderr) {
  auto r =
      sh("i=0; while [ $i -lt 3000 ]; do echo line-$i >&2; i=$((i+1)); done; echo THE-END >&2");
  EXPECT_LE(r.stderr_tail.size(), 4096u);
  EXPECT_NE(r.stderr_tail.find("THE-END"), std::string::npos);
}

TEST(Runner, SignalIsReported) {
  auto r = sh("kill -SEGV $$");
  EXPECT_EQ(r.outcome, Outcome::signaled);
  EXPECT_EQ(r.signal, SIGSEGV);
}

TEST(Runner, EnvironmentIsExactlyWhatWasGiven) {
  auto r = sh("echo \"$OMP_NUM_THREADS/$OMP_PROC_BIND/${HOME:-nohome}\" >&2", 10,
              {"PATH=/bin", "OMP_NUM_THREADS=3", "OMP_PROC_BIND=close"});
  EXPECT_EQ(r.stderr_tail, "3/close/nohome\n");
}

TEST(Runner, MissingProgramFailsWith127) {
  auto r = run_child({"/nonexistent/psim"}, {}, 5, nullptr);
  EXPECT_EQ(r.outcome, Outcome::exited);
  EXPECT_EQ(r.exit_code, 127);
  EXPECT_NE(r.stderr_tail.find("cannot execute /nonexistent/psim"), std::string::npos);
}

TEST(Runner, TimeoutKillsTheWholeProcessGroup) {
  const std::string pidfile = ::testing::TempDir() + "psweep_grandchild.pid";
  std::remove(pidfile.c_str());
  auto start = std::chrono::steady_clock::now();
  // the grandchild holds stderr open and would outlive a kill of the shell alone
  auto r = sh("sleep 30 & echo $! > " + pidfile + "; echo started >&2; wait", 0.5);
  double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.outcome, Outcome::timed_out);
  EXPECT_GE(took, 0.5);
  EXPECT_LT(took, 3.0);
  EXPECT_EQ(r.stderr_tail, "started\n");
  pid_t grandchild = 0;
  std::ifstream(pidfile) >> grandchild;
  ASSERT_GT(grandchild, 0);
  bool gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {  // SIGKILL delivery and reaping by init take a moment
    gone =
        kill(grandchild, 0) != 0 || process_state(grandchild) == 'Z';  // dead, maybe not yet reaped
    if (!gone) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(gone) << "grandchild " << grandchild << " survived the timeout";
  std::remove(pidfile.c_str());
}

TEST(Runner, RusageAndSoftwareCounters) {
  CounterAvailability available = probe_counters();
  auto r = sh("i=0; while [ $i -lt 20000 ]; do i=$((i+1)); done", 10, {"PATH=/bin"}, &available);
  EXPECT_EQ(r.outcome, Outcome::exited);
  double user = static_cast<double>(r.usage.ru_utime.tv_sec) + r.usage.ru_utime.tv_usec * 1e-6;
  EXPECT_GT(user + r.usage.ru_stime.tv_usec * 1e-6, 0);
  EXPECT_GT(r.usage.ru_maxrss, 0);
  if (!available.software) {
    GTEST_SKIP() << available.note;
  }
  ASSERT_TRUE(r.events.task_clock_s);
  EXPECT_GT(*r.events.task_clock_s, 0);
  EXPECT_LE(*r.events.task_clock_s, r.process_s * 1.5);
  ASSERT_TRUE(r.events.page_faults);
  EXPECT_GT(*r.events.page_faults, 0u);
  if (!available.hardware) {
    EXPECT_FALSE(r.events.cycles);
  }
}

TEST(Runner, CaptureOutput) {
  EXPECT_EQ(capture_output({"/bin/echo", "brute"}), std::optional<std::string>("brute\n"));
  EXPECT_FALSE(capture_output({"/bin/false"}));
  EXPECT_FALSE(capture_output({"/nonexistent"}));
}

TEST(Runner, NoDescriptorOfPsweepsReachesTheChildEvenWithoutCloseOnExec) {
  // As a std::ifstream's: opened without O_CLOEXEC, open while the child starts.
  const int leaked = open("/dev/null", O_RDONLY);
  ASSERT_GE(leaked, 3);
  auto r = sh("ls /proc/self/fd >&2");
  close(leaked);
  // 0, 1, 2 and ls's own descriptor of the listing.
  EXPECT_EQ(r.stderr_tail, "0\n1\n2\n3\n");
}
