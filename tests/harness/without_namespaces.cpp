// without_namespaces COMMAND...: runs COMMAND where no new namespace can be made, as in Docker's
// default seccomp profile (and so Gradescope's and most CI containers): the contained tier's own
// filter (run/seccomp.hpp: no unshare, no namespace flags to clone, no clone3, no mount), which
// is at least as strict. The confinement tests grade inside it.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "run/seccomp.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: without_namespaces COMMAND [ARG...]\n");
    return 2;
  }
  if (!psweep::forbid_escapes()) {
    std::fprintf(stderr, "without_namespaces: the kernel refused the seccomp filter\n");
    return 1;
  }
  execvp(argv[1], argv + 1);
  std::fprintf(stderr, "without_namespaces: cannot run %s: %s\n", argv[1], std::strerror(errno));
  return 127;
}
