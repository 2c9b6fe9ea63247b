// Containment: the tier without namespaces (run/tier.hpp), for machines that refuse them (Docker's
// default seccomp profile, hence Gradescope's and most CI containers). Each run:
//   - as a user of its own when psweep is root (run/run_user.hpp), else as psweep's user;
//   - in a fresh folder of its own in the stage (its HOME, TMPDIR and working folder), removed
//     after it, and killed when it holds more than disk_mib or a file per 4 KiB of it
//     (run/folder_limit.hpp);
//   - Landlock: reads and executes only the system's folders (/usr, /etc, /bin, /lib), /proc,
//     /sys, /dev and its staged files; writes only its folder and /dev/null; no TCP (ABI 4); no
//     signal to a process outside its own tree (ABI 6);
//   - seccomp (run/seccomp.hpp): no socket (socketpair stays), no SysV IPC, message queue or
//     memfd, no ptrace, namespace or mount call;
//   - the limits set directly (CPU, memory, address space, stack, threads, open files, file
//     size);
//   - afterwards every process it left, setsid daemons included, killed: psweep is their
//     subreaper (run/runner.hpp, ChildIo::confined), and every process of its user is killed.
// What it cannot hold: its folder's size between two of psweep's looks at it (what a program
// writes in 100 ms past the limit), the network namespace's loopback-only view (seccomp refuses
// the sockets instead), other users' entries in /proc (docs/faults.md).
#pragma once

#include <sys/resource.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "run/landlock.hpp"
#include "run/tier.hpp"

namespace psweep {

// What a contained run's process sets up for itself between fork and exec.
struct Containment {
  std::string folder;
  const PathRules* paths = nullptr;
  int landlock_abi = 0;
  std::vector<std::pair<int, rlimit>> limits;
};

// In the forked child before exec (its user and CPUs set): its folder, limits, Landlock and
// seccomp. False when the kernel refused one. Async-signal-safe.
bool enter_containment(const Containment& c);

// The contained tier; nullptr and `why` where Landlock or seccomp is missing.
std::unique_ptr<Tier> contained_tier(std::string& why);

}  // namespace psweep
