// Runner: one child process, measured and bounded.
//
// fork + exec with a handshake: the child makes itself a process-group leader, then waits on a
// pipe until the parent has attached the perf counters, then execs; stdin and stdout go to
// /dev/null or the files ChildIo names, stderr to a pipe of which the last few KiB are kept. The
// parent waits with poll() on a pidfd, the stderr pipe and the interrupt self-pipe, so a timeout or
// SIGINT/SIGTERM kills the whole process group at once, without polling loops. rusage comes from
// wait4.
#pragma once

#include <sys/resource.h>
#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "run/counters.hpp"
#include "run/folder_limit.hpp"

namespace psweep {

// over_limit: killed by psweep for a limit no kernel mechanism held (ChildResult::over).
enum class Outcome { exited, signaled, timed_out, interrupted, over_limit };

struct ChildResult {
  Outcome outcome = Outcome::exited;
  int exit_code = 0;        // when exited
  int signal = 0;           // when signaled
  double process_s = 0;     // fork to reap, steady clock
  struct rusage usage {};   // of the child and its reaped descendants (ChildIo::confined)
  std::string stderr_tail;  // the last bytes the child wrote on stderr
  std::string over;         // when over_limit: which, in words
  EventCounts events;
};

// Where the child's stdin and stdout go: /dev/null unless a path is given. An external program
// reads its scene from `stdin_path` and prints into `stdout_path`; `file_size_limit` (bytes,
// RLIMIT_FSIZE) stops one that prints without end: the kernel sends it SIGXFSZ at the limit.
struct ChildIo {
  std::string stdin_path, stdout_path;
  std::uint64_t file_size_limit = 0;  // 0: none
  int uid = -1, gid = -1;             // the user it runs as; -1: psweep's (run/run_user.hpp)
  bool own_user = false;              // that user is this psweep's alone: its processes killed after
  std::vector<int> cpus;              // the CPUs it may run on; empty: psweep's
  // A confined run: it binds its threads within `cpus` and never beyond (run/affinity.hpp), and
  // what it leaves behind comes to psweep (a subreaper), is killed, and its rusage counted: a
  // sandbox's init, which reaped the program, among them.
  bool confined = false;
  // The contained tier's set-up (run/contain.hpp); its leftovers are killed after it. Not owned.
  const struct Containment* contain = nullptr;
  FolderLimit folder;  // its writable folder's size where no file system bounds it
};

// Runs argv[0] (a path) with `env`. `counters` may be null (no perf events). Throws
// std::runtime_error when `io`'s files cannot be opened.
ChildResult run_child(const std::vector<std::string>& argv, const std::vector<std::string>& env,
                      double timeout_s, const CounterAvailability* counters,
                      const ChildIo& io = {});

// For a forked child before anything else: SIGKILL when `parent` (the forking process) ends, so
// a psweep killed outright (kill -9, OOM) leaves no run or spinner behind to spoil the timings of
// the sweep resumed after it. The parent may already be gone when it is set: then the child ends
// at once. Async-signal-safe.
void die_with_parent(pid_t parent);

// SIGINT and SIGTERM set a flag and wake run_child, which kills its child; the sweep then stops.
void install_interrupt_handlers();
// The signal received (SIGINT or SIGTERM), or 0.
int interrupt_signal();

}  // namespace psweep

namespace psweep {

// Runs argv (argv[0] a path) to completion and returns its stdout, or nullopt when it cannot be
// started or exits nonzero. For short queries such as `psim --list-engines`.
std::optional<std::string> capture_output(const std::vector<std::string>& argv);

}  // namespace psweep
