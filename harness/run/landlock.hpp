// Landlock: what a contained run (the tier without namespaces, run/contain.hpp) may reach of the
// file system, the network and other processes, enforced by the kernel whatever the program is.
#pragma once

#include <string>
#include <vector>

namespace psweep {

// The kernel's Landlock ABI version; 0 where it has none, or where a seccomp policy (a
// container's) refuses the call.
int landlock_abi();

// Paths a contained run may reach, opened before the fork (each an O_PATH descriptor, closed on
// exec): read and execute beneath `readable`, read and write the files `devices` (/dev/null),
// everything beneath `writable`.
struct PathRules {
  std::vector<int> readable, devices, writable;
  PathRules(const std::vector<std::string>& readable, const std::vector<std::string>& devices,
            const std::vector<std::string>& writable);
  ~PathRules();
  PathRules(const PathRules&) = delete;
  PathRules& operator=(const PathRules&) = delete;
};

// In a forked child before exec: from here on this process and all it starts reach only `rules`'
// paths, make no TCP connection (ABI 4 and later) and signal no process outside (ABI 6 and
// later). Sets no_new_privs. False when the kernel refused. Async-signal-safe.
bool restrict_to(const PathRules& rules, int abi);

}  // namespace psweep
