// The affinity keeper (run/affinity.hpp) through run_child: a confined run binds within its CPUs,
// is cut to them, is refused elsewhere; and where a listener exists already, the call succeeds
// without effect.
#include <gtest/gtest.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

#include "run/runner.hpp"

using namespace psweep;

namespace {

// The CPUs this process may run on.
std::vector<int> own_cpus() {
  cpu_set_t set;
  sched_getaffinity(0, sizeof set, &set);
  std::vector<int> cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return cpus;
}

// The hex mask taskset reads for one CPU.
std::string mask_of(int cpu) {
  char text[32];
  std::snprintf(text, sizeof text, "%llx", 1ULL << cpu);
  return text;
}

// A confined shell's affinity (taskset's list) after it asked for `mask` (hex), with "refused"
// before it when the call failed.
ChildResult confined_taskset(const std::string& mask, std::vector<int> cpus) {
  ChildIo io;
  io.cpus = std::move(cpus);
  io.confined = true;
  return run_child({"/bin/sh", "-c",
                    "{ taskset " + mask + " sh -c 'taskset -cp $$' 2>/dev/null || "
                    "{ echo refused; taskset -cp $$; }; } | sed 's/.*: //' >&2"},
                   {"PATH=/usr/bin:/bin"}, 10, nullptr, io);
}

}  // namespace

TEST(Affinity, ABindingInsideTheRunsCpusIsTheOneAskedFor) {
  const std::vector<int> cpus = own_cpus();
  if (cpus.size() < 2) GTEST_SKIP() << "needs two CPUs";
  const ChildResult r = confined_taskset(mask_of(cpus[1]), {cpus[0], cpus[1]});
  EXPECT_EQ(r.stderr_tail, std::to_string(cpus[1]) + "\n");
}

TEST(Affinity, EveryCpuAskedForIsCutToTheRunsOwn) {
  const std::vector<int> cpus = own_cpus();
  const ChildResult r = confined_taskset("ffffffffffffffff", {cpus[0]});
  EXPECT_EQ(r.stderr_tail, std::to_string(cpus[0]) + "\n");
}

TEST(Affinity, ACpuOutsideTheRunsIsRefused) {
  const std::vector<int> cpus = own_cpus();
  if (cpus.size() < 2) GTEST_SKIP() << "needs two CPUs";
  const ChildResult r = confined_taskset(mask_of(cpus[1]), {cpus[0]});
  EXPECT_EQ(r.stderr_tail, "refused\n" + std::to_string(cpus[0]) + "\n");
}

TEST(Affinity, UnderAnotherListenerTheCallSucceedsWithoutEffect) {
  const std::vector<int> cpus = own_cpus();
  if (cpus.size() < 2) GTEST_SKIP() << "needs two CPUs";
  const pid_t pid = fork();
  if (pid == 0) {  // as a container whose filter holds the one listener, for other calls
    static sock_filter allow[] = {BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW)};
    static sock_fprog program = {1, allow};
    if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
        syscall(SYS_seccomp, SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_NEW_LISTENER,
                &program) < 0)
      _exit(10);
    const ChildResult r = confined_taskset(mask_of(cpus[1]), {cpus[0]});
    _exit(r.stderr_tail == std::to_string(cpus[0]) + "\n" ? 0 : 11);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}
