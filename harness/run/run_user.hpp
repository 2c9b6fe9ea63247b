// The runs' user: where psweep is root, every confined run (and everything it starts) runs as a
// user of this psweep's own, taken from a range no account uses and held for the process's life
// by a lock, so that no other psweep on the machine (a second `make grade`, another Slurm task on
// the node) runs as it at the same time. Then, after each run:
//   - every process of that user is killed by a process of that user (kill(-1)), however it
//     forked, setsid or double fork, in or out of psweep's sight (issue 57: chains of setsid and
//     fork outlived a grading);
//   - RLIMIT_NPROC, which the kernel counts per user and in threads, counts the next run's
//     threads alone (a survivor's sleeping threads once starved a threaded classmate).
// Runs stay one at a time under it: psweep runs its programs one after another.
// Where psweep is not root, runs keep psweep's user (it cannot change), and the sandbox's PID
// namespace, or the subreaper (run/runner.hpp), ends what they leave.
#pragma once

#include "run/runner.hpp"

namespace psweep {

// The first uid and the size of the range tried first (its gid the same number), and the one tried
// where a container's user namespace maps no such ids: the 1024 below 65534 (`nobody`). A uid an
// account names (/etc/passwd) is skipped; if none is free, runs are `nobody`'s, shared.
constexpr int kRunUsersFirst = 0x7f000000;
constexpr int kRunUsersCount = 1024;

// io.uid and io.gid: this psweep's own runs' user when psweep is root (taken on the first call,
// every process and SysV object left of it by an earlier holder killed or removed); untouched
// otherwise.
void run_as_own_user_if_root(ChildIo& io);

// Kills every process of `uid` (not root's), from a forked process of that uid. Those whose
// parent is psweep (a subreaper) are left for it to reap.
void kill_every_process_of(int uid, int gid);

}  // namespace psweep
