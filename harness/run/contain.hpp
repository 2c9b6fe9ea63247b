// Containment: the tier without namespaces (run/tier.hpp), for machines that refuse them (Docker's
// default seccomp profile, hence Gradescope's and most CI containers). Each run:
//   - as `nobody` when psweep is root (there root keeps CAP_SETUID), else as psweep's user;
//   - in a fresh folder of its own in the stage (its HOME, TMPDIR and working folder), removed
//     after it;
//   - Landlock: reads and executes only the system's folders (/usr, /etc, /bin, /lib), /proc,
//     /sys, /dev and its staged files; writes only its folder and /dev/null; no TCP (ABI 4); no
//     signal to a process outside its own tree (ABI 6);
//   - seccomp (run/seccomp.hpp): no socket but AF_UNIX, no ptrace, namespace or mount call;
//   - the limits set directly (CPU, memory, address space, stack, processes, open files, file
//     size);
//   - afterwards every process it left, setsid daemons included, killed: psweep is their
//     subreaper (run/runner.hpp, ChildIo::confined).
// What it cannot hold: a disk limit for its folder (RLIMIT_FSIZE bounds each file, not their
// number), the network namespace's loopback-only view (seccomp refuses the sockets instead).
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
