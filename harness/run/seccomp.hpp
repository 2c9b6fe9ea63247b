// Seccomp: system calls a confined program may not make, refused by the kernel whatever the
// program is (a filter survives exec and is inherited by every process and thread it starts).
#pragma once

namespace psweep {

// From here on (this process and everything it execs or starts), sched_setaffinity fails with
// EPERM, in every ABI this machine runs: a program keeps the CPUs psweep pinned it to, where it
// once widened a T = 1 run to every CPU (issue 40). Sets no_new_privs, as a filter needs. For a
// forked child before exec: async-signal-safe. False when the kernel refused the filter.
bool forbid_affinity_change();

// For the contained tier (run/contain.hpp), where no namespace isolates the run: from here on no
// socket but AF_UNIX (EACCES), no ptrace or access to another process's memory, no namespace,
// mount, chroot, BPF, perf event, io_uring or keyring call (EPERM), no clone3 (ENOSYS: the C
// library falls back to clone, whose namespace flags are refused), and no system call of another
// ABI (a 32-bit program does not run). Sets no_new_privs. False when the kernel refused the
// filter. Async-signal-safe.
bool forbid_escapes();

}  // namespace psweep
