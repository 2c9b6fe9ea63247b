// The affinity keeper: psweep's answer to a confined run's sched_setaffinity calls.
//
// A run is pinned to its T CPUs, and it must stay there: a T = 1 run once widened itself to every
// CPU (issue 40). Refusing the call outright (EPERM) kept it there, but libgomp binds each thread
// it starts with that call when OMP_PROC_BIND is set, and stopped every OpenMP program with
// "Thread creation failed" (issue 56). So the call is not refused but answered: the run's filter
// (run/seccomp.hpp) hands it to psweep, which reads the mask the program asked for, keeps the part
// inside the run's CPUs and applies that itself, as the kernel does for a task in a cpuset: a
// binding inside the set is the one asked for, a mask partly outside it is cut to the set, one
// wholly outside fails with EINVAL. The mask applied is psweep's own copy, read once, so a
// program that rewrites its mask after the call changes nothing. A thread may set its own
// affinity or another thread's of its process (pthread_create with an affinity attribute sets the
// new thread's from its creator); any other target gets ESRCH.
#pragma once

#include <vector>

namespace psweep {

class AffinityKeeper {
 public:
  // `listener`: the filter's descriptor (run/seccomp.hpp's supervise_affinity), owned from here;
  // `cpus`: the run's CPUs (none: psweep's own, where the run was not pinned).
  AffinityKeeper(int listener, std::vector<int> cpus);
  ~AffinityKeeper();
  AffinityKeeper(const AffinityKeeper&) = delete;
  AffinityKeeper& operator=(const AffinityKeeper&) = delete;

  // The descriptor to poll: readable when a call waits, hung up when every process of the run
  // has ended.
  int fd() const { return listener_; }
  // Answers the call that waits (poll said so); a call whose thread died meanwhile is dropped.
  void answer();

 private:
  int listener_;
  std::vector<int> cpus_;
};

}  // namespace psweep
