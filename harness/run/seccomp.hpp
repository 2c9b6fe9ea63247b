// Seccomp: system calls a confined program may not make, refused by the kernel whatever the
// program is (a filter survives exec and is inherited by every process and thread it starts).
#pragma once

namespace psweep {

// From here on (this process and everything it execs or starts), every sched_setaffinity, in
// every ABI this machine runs, waits for the supervisor that reads the returned descriptor (the
// filter's listener, close-on-exec) and answers in its stead (run/affinity.hpp): a program binds
// its threads within the CPUs psweep pinned it to, and never beyond them, where it once widened a
// T = 1 run to every CPU (issue 40). Sets no_new_privs, as a filter needs. For a forked child
// before exec: async-signal-safe. Where a filter already holds the one listener a task may have
// (a container's, or an outer psweep's), the call succeeds without effect instead, the run kept on
// its CPUs, and kNoSupervisor comes back; -1 when the kernel refused the filter (before Linux 5.0).
// The same filter refuses (EPERM), in both tiers, what a run could share with a later one or hold
// past memory_mib: SysV IPC objects, POSIX message queues and memfds.
constexpr int kNoSupervisor = -2;
int supervise_affinity();

// For the contained tier (run/contain.hpp), where no namespace isolates the run: from here on no
// socket (EACCES; socketpair stays), no ptrace or access to another process's memory, no
// namespace, mount, chroot, BPF, perf event, io_uring or keyring call (EPERM), no clone3 (ENOSYS:
// the C library falls back to clone, whose namespace flags are refused), and no system call of
// another ABI (a 32-bit program does not run). Sets no_new_privs. False when the kernel refused
// the filter. Async-signal-safe.
bool forbid_escapes();

}  // namespace psweep
