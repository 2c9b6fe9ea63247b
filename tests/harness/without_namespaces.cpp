// without_namespaces COMMAND...: runs COMMAND where no new namespace can be made, as in Docker's
// default seccomp profile (and so Gradescope's and most CI containers): no unshare, setns, mount
// or pivot_root (EPERM), no namespace flags to clone (EPERM), no clone3 (ENOSYS, so that the C
// library falls back to clone); everything else allowed, as Docker allows it (sockets, SysV IPC,
// memfds: what the contained tier's own filter must refuse to its runs). The confinement tests
// grade inside it.
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>

namespace {

constexpr unsigned kNamespaces = CLONE_NEWNS | CLONE_NEWCGROUP | CLONE_NEWUTS | CLONE_NEWIPC |
                                 CLONE_NEWUSER | CLONE_NEWPID | CLONE_NEWNET | 0x80 /* NEWTIME */;
constexpr unsigned kPermission = SECCOMP_RET_ERRNO | EPERM;

bool forbid_namespaces() {
  constexpr unsigned nr = offsetof(seccomp_data, nr);
  constexpr unsigned arg0 = offsetof(seccomp_data, args);
  static sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, nr),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_unshare, 5, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_setns, 4, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_mount, 3, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_pivot_root, 2, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_clone3, 2, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, SYS_clone, 2, 5),
      BPF_STMT(BPF_RET | BPF_K, kPermission),                   // [7]
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | ENOSYS),    // [8]
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, arg0),                 // [9]: clone's flags
      BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, kNamespaces, 0, 1),
      BPF_STMT(BPF_RET | BPF_K, kPermission),
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),
  };
  static sock_fprog program = {static_cast<unsigned short>(sizeof filter / sizeof filter[0]),
                               filter};
  return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 &&
         prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: without_namespaces COMMAND [ARG...]\n");
    return 2;
  }
  if (!forbid_namespaces()) {
    std::fprintf(stderr, "without_namespaces: the kernel refused the seccomp filter\n");
    return 1;
  }
  execvp(argv[1], argv + 1);
  std::fprintf(stderr, "without_namespaces: cannot run %s: %s\n", argv[1], std::strerror(errno));
  return 127;
}
