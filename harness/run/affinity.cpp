// The affinity keeper: see affinity.hpp.
#include "run/affinity.hpp"

#include <fcntl.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace psweep {
namespace {

// The kernel's structures may grow past the headers': buffers of the sizes it says.
struct Sizes {
  std::size_t notif = sizeof(seccomp_notif), resp = sizeof(seccomp_notif_resp);
  Sizes() {
    seccomp_notif_sizes s{};
    if (syscall(SYS_seccomp, SECCOMP_GET_NOTIF_SIZES, 0, &s) == 0) {
      notif = std::max<std::size_t>(notif, s.seccomp_notif);
      resp = std::max<std::size_t>(resp, s.seccomp_notif_resp);
    }
  }
};

// A task's ids from the outermost PID namespace /proc sees (psweep's) to its own: the NSpid line.
std::vector<long> namespace_ids(const std::filesystem::path& status) {
  std::ifstream in(status);
  std::vector<long> ids;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("NSpid:", 0) != 0) continue;
    std::istringstream fields(line.substr(6));
    for (long id; fields >> id;) ids.push_back(id);
  }
  return ids;
}

// psweep's id of the thread `target` names in its caller's PID namespace (0: the caller itself),
// looked for among the caller's own threads; -1 when it is none of them. The caller first, from
// its own status: it waits in its call, so that is always there. Another thread is looked for in
// /proc's task folder, whose walk ends early, missing every thread after it, when the thread it
// stands on exits meanwhile (the kernel's next_tid): a pthreads program's thread pinning itself
// while its sibling ended got ESRCH in about one run of a hundred. So a miss is walked again.
long thread_of(long caller, long target) {
  if (target == 0) return caller;
  const std::string proc = "/proc/" + std::to_string(caller);
  const std::vector<long> own = namespace_ids(proc + "/status");
  if (!own.empty() && own.back() == target) return caller;
  constexpr int kWalks = 4;
  for (int walk = 0; walk < kWalks; ++walk) {
    std::error_code ec;
    for (const auto& task : std::filesystem::directory_iterator(proc + "/task", ec)) {
      const std::vector<long> ids = namespace_ids(task.path() / "status");
      if (!ids.empty() && ids.back() == target) return ids.front();
    }
  }
  return -1;
}

// The mask the caller asked for, from its memory: zero bits past `bytes`, as the kernel reads a
// short mask; false when the address cannot be read. Through /proc, not process_vm_readv, which
// a container's seccomp profile may refuse psweep itself.
bool read_mask(long caller, std::uint64_t address, std::uint64_t bytes, cpu_set_t& mask) {
  CPU_ZERO(&mask);
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(bytes, sizeof mask));
  const int memory =
      open(("/proc/" + std::to_string(caller) + "/mem").c_str(), O_RDONLY | O_CLOEXEC);
  if (memory < 0) return false;
  const bool read =
      n == 0 || pread(memory, &mask, n, static_cast<off_t>(address)) == static_cast<ssize_t>(n);
  close(memory);
  return read;
}

}  // namespace

AffinityKeeper::AffinityKeeper(int listener, std::vector<int> cpus)
    : listener_(listener), cpus_(std::move(cpus)) {
  cpu_set_t own;
  if (!cpus_.empty() || sched_getaffinity(0, sizeof own, &own) != 0) return;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &own)) cpus_.push_back(cpu);
}

AffinityKeeper::~AffinityKeeper() {
  if (listener_ >= 0) close(listener_);
}

void AffinityKeeper::answer() {
  static const Sizes sizes;
  std::vector<unsigned char> notif_buffer(sizes.notif), resp_buffer(sizes.resp);
  auto* call = reinterpret_cast<seccomp_notif*>(notif_buffer.data());
  auto* reply = reinterpret_cast<seccomp_notif_resp*>(resp_buffer.data());
  if (ioctl(listener_, SECCOMP_IOCTL_NOTIF_RECV, call) != 0) return;  // its thread is gone
  reply->id = call->id;
  const long caller = call->pid;  // in psweep's PID namespace: the kernel translates it
  cpu_set_t wanted, applied;
  CPU_ZERO(&applied);
  const long target = thread_of(caller, static_cast<long>(call->data.args[0]));
  if (!read_mask(caller, call->data.args[2], call->data.args[1], wanted)) {
    reply->error = -EFAULT;
  } else if (target < 0) {
    reply->error = -ESRCH;
  } else {
    for (int cpu : cpus_)
      if (CPU_ISSET(cpu, &wanted)) CPU_SET(cpu, &applied);
    // The ids read are the caller's only while its call waits (NOTIF_ID_VALID): a thread that
    // died since may have left its id to another process.
    if (CPU_COUNT(&applied) == 0) {
      reply->error = -EINVAL;
    } else if (ioctl(listener_, SECCOMP_IOCTL_NOTIF_ID_VALID, &call->id) != 0) {
      return;
    } else if (sched_setaffinity(static_cast<pid_t>(target), sizeof applied, &applied) != 0) {
      reply->error = -errno;
    }
  }
  ioctl(listener_, SECCOMP_IOCTL_NOTIF_SEND, reply);
}

}  // namespace psweep
