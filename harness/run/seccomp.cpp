// Seccomp: see seccomp.hpp. A classic BPF filter written out by hand: a library (libseccomp)
// would be a dependency for four instructions per ABI.
#include "run/seccomp.hpp"

#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sys/prctl.h>
#include <sys/syscall.h>

#include <cerrno>
#include <cstddef>

namespace psweep {
namespace {

#if defined(__x86_64__)
constexpr unsigned kArch = AUDIT_ARCH_X86_64;
// 32-bit x86 programs run here too, with their own numbers; x32's are x86-64's with this bit.
constexpr unsigned kCompatArch = AUDIT_ARCH_I386;
constexpr unsigned kCompatAffinity = 241;  // sched_setaffinity on i386
constexpr unsigned kX32Bit = 0x40000000;
#elif defined(__aarch64__)
constexpr unsigned kArch = AUDIT_ARCH_AARCH64;
constexpr unsigned kCompatArch = AUDIT_ARCH_ARM;
constexpr unsigned kCompatAffinity = 241;  // sched_setaffinity on 32-bit ARM
constexpr unsigned kX32Bit = 0;
#else
#error "psweep's seccomp filter knows x86-64 and AArch64"
#endif

constexpr unsigned kRefuse = SECCOMP_RET_ERRNO | (EPERM & SECCOMP_RET_DATA);

}  // namespace

bool forbid_affinity_change() {
  constexpr unsigned arch = offsetof(seccomp_data, arch);
  constexpr unsigned nr = offsetof(seccomp_data, nr);
  static sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, arch),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kArch, 0, 5),  // else: the compat ABI, at [7]
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, nr),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_sched_setaffinity, 2, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kX32Bit | SYS_sched_setaffinity, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
      BPF_STMT(BPF_RET | BPF_K, kRefuse),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kCompatArch, 0, 3),  // [7]; else allowed
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, nr),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kCompatAffinity, 0, 1),
      BPF_STMT(BPF_RET | BPF_K, kRefuse),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  static sock_fprog program = {static_cast<unsigned short>(sizeof filter / sizeof filter[0]),
                               filter};
  return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 &&
         prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) == 0;
}

}  // namespace psweep
