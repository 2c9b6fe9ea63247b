// Seccomp: see seccomp.hpp. A classic BPF filter written out by hand: a library (libseccomp)
// would be a dependency for four instructions per ABI.
#include "run/seccomp.hpp"

#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <iterator>

namespace psweep {
namespace {

#if defined(__x86_64__)
constexpr unsigned kArch = AUDIT_ARCH_X86_64;
// 32-bit x86 programs run here too, with their own numbers; x32's are x86-64's with this bit.
constexpr unsigned kCompatArch = AUDIT_ARCH_I386;
constexpr unsigned kCompatAffinity = 241;  // sched_setaffinity on i386
// i386's memfd_create, ipc (the SysV multiplexer), shmget, semget, msgget and mq_open
constexpr unsigned kCompatShared[] = {356, 117, 395, 393, 399, 277};
constexpr unsigned kX32Bit = 0x40000000;
#elif defined(__aarch64__)
constexpr unsigned kArch = AUDIT_ARCH_AARCH64;
constexpr unsigned kCompatArch = AUDIT_ARCH_ARM;
constexpr unsigned kCompatAffinity = 241;  // sched_setaffinity on 32-bit ARM
// 32-bit ARM's memfd_create, shmget, semget, msgget and mq_open
constexpr unsigned kCompatShared[] = {385, 307, 299, 303, 274};
constexpr unsigned kX32Bit = 0;
#else
#error "psweep's seccomp filter knows x86-64 and AArch64"
#endif

// What a run could share with a later run or hold past memory_mib, refused in both tiers (issue
// 57): a SysV segment outlived its process and cached the answers of later repetitions; memfds
// filled with fallocate held 8 GiB past memory_mib, counted by no limit.
constexpr unsigned kShared[] = {SYS_memfd_create, SYS_shmget, SYS_semget, SYS_msgget,
                                SYS_mq_open};

constexpr sock_filter stmt(unsigned short code, unsigned k) { return BPF_STMT(code, k); }
constexpr sock_filter jump(unsigned short code, unsigned k, unsigned char jt, unsigned char jf) {
  return BPF_JUMP(code, k, jt, jf);
}
constexpr unsigned errno_of(int e) { return SECCOMP_RET_ERRNO | (e & SECCOMP_RET_DATA); }

// sched_setaffinity, in every ABI, to `action`; kShared refused (EPERM); every other call
// allowed. Static: built in the child between fork and exec, without allocating.
sock_fprog affinity_program(unsigned action) {
  constexpr unsigned arch = offsetof(seccomp_data, arch);
  constexpr unsigned nr = offsetof(seccomp_data, nr);
  static sock_filter code[2 * (std::size(kShared) + std::size(kCompatShared)) + 16];
  std::size_t n = 0;
  const auto put = [&](sock_filter f) { code[n++] = f; };
  const auto refuse = [&](unsigned call, unsigned to) {
    put(jump(BPF_JMP | BPF_JEQ | BPF_K, call, 0, 1));
    put(stmt(BPF_RET | BPF_K, to));
  };
  put(stmt(BPF_LD | BPF_W | BPF_ABS, arch));
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, kArch, 0, static_cast<unsigned char>(
                                                  3 + 2 * (std::size(kShared) + 1))));
  put(stmt(BPF_LD | BPF_W | BPF_ABS, nr));
  put(stmt(BPF_ALU | BPF_AND | BPF_K, ~kX32Bit));  // x32's numbers are x86-64's
  refuse(SYS_sched_setaffinity, action);
  for (unsigned call : kShared) refuse(call, errno_of(EPERM));
  put(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  // The compat ABI; any other (none runs here) allowed, as the kernel refuses to run it.
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, kCompatArch, 1, 0));
  put(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  put(stmt(BPF_LD | BPF_W | BPF_ABS, nr));
  refuse(kCompatAffinity, action);
  for (unsigned call : kCompatShared) refuse(call, errno_of(EPERM));
  put(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  return {static_cast<unsigned short>(n), code};
}

}  // namespace

int supervise_affinity() {
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) return -1;
  sock_fprog program = affinity_program(SECCOMP_RET_USER_NOTIF);
  const long listener =
      syscall(SYS_seccomp, SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_NEW_LISTENER, &program);
  if (listener >= 0 || errno != EBUSY) return static_cast<int>(listener);
  // A filter of the container's (or of a psweep psweep runs) has the one listener a task may
  // have: the call succeeds without effect, so the run keeps its CPUs and a runtime's binding
  // goes on, unbound.
  program = affinity_program(SECCOMP_RET_ERRNO | 0);
  return prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) == 0 ? kNoSupervisor : -1;
}

namespace {

constexpr unsigned kNamespaces = CLONE_NEWNS | CLONE_NEWCGROUP | CLONE_NEWUTS | CLONE_NEWIPC |
                                 CLONE_NEWUSER | CLONE_NEWPID | CLONE_NEWNET | 0x80 /* NEWTIME */;

// Each block jumps only within itself, so the program is written in order, without labels.
sock_fprog escapes_program() {
  constexpr unsigned arch = offsetof(seccomp_data, arch);
  constexpr unsigned nr = offsetof(seccomp_data, nr);
  constexpr unsigned arg0 = offsetof(seccomp_data, args);  // the low half, little-endian
  constexpr long kRefused[] = {
      SYS_ptrace,
      SYS_process_vm_readv,
      SYS_process_vm_writev,
      SYS_unshare,
      SYS_setns,
      SYS_mount,
      SYS_umount2,
      SYS_pivot_root,
      SYS_chroot,
      SYS_bpf,
      SYS_perf_event_open,
      SYS_io_uring_setup,
      SYS_keyctl,
      SYS_add_key,
      SYS_request_key,
      SYS_open_tree,
      SYS_move_mount,
      SYS_fsopen,
      SYS_fsconfig,
      SYS_fsmount,
      SYS_fspick,
      SYS_mount_setattr,
      SYS_userfaultfd,
  };
  static sock_filter code[2 * std::size(kRefused) + 32];
  std::size_t n = 0;
  const auto put = [&](sock_filter f) { code[n++] = f; };
  put(stmt(BPF_LD | BPF_W | BPF_ABS, arch));
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, kArch, 1, 0));
  put(stmt(BPF_RET | BPF_K, errno_of(ENOSYS)));
  put(stmt(BPF_LD | BPF_W | BPF_ABS, nr));
  if (kX32Bit) {
    put(jump(BPF_JMP | BPF_JGE | BPF_K, kX32Bit, 0, 1));
    put(stmt(BPF_RET | BPF_K, errno_of(ENOSYS)));
  }
  for (long call : kRefused) {
    put(jump(BPF_JMP | BPF_JEQ | BPF_K, static_cast<unsigned>(call), 0, 1));
    put(stmt(BPF_RET | BPF_K, errno_of(EPERM)));
  }
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, SYS_clone3, 0, 1));
  put(stmt(BPF_RET | BPF_K, errno_of(ENOSYS)));
  // No socket at all (socketpair, a separate call, stays): Landlock does not check connect on a
  // path-named Unix socket, and a run once wrote to a host's socket outside every rule.
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, SYS_socket, 0, 1));
  put(stmt(BPF_RET | BPF_K, errno_of(EACCES)));
  put(jump(BPF_JMP | BPF_JEQ | BPF_K, SYS_clone, 0, 4));
  put(stmt(BPF_LD | BPF_W | BPF_ABS, arg0));
  put(jump(BPF_JMP | BPF_JSET | BPF_K, kNamespaces, 0, 1));
  put(stmt(BPF_RET | BPF_K, errno_of(EPERM)));
  put(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  put(stmt(BPF_RET | BPF_K, SECCOMP_RET_ALLOW));
  return {static_cast<unsigned short>(n), code};
}

// Built before any fork: the child only installs it.
const sock_fprog kEscapes = escapes_program();

}  // namespace

bool forbid_escapes() {
  return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 &&
         prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &kEscapes) == 0;
}

}  // namespace psweep
