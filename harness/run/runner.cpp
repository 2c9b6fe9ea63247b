#include "run/runner.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <grp.h>
#include <linux/close_range.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/sendfile.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

#include "run/affinity.hpp"
#include "run/contain.hpp"
#include "run/run_user.hpp"
#include "run/seccomp.hpp"

namespace psweep {
namespace {

constexpr std::size_t stderr_keep = 4096;

volatile std::sig_atomic_t received_signal = 0;
int wake_pipe[2] = {-1, -1};

void on_signal(int sig) {
  int saved = errno;
  if (received_signal != 0) {  // impatience: say that the stop is under way, not stuck
    static const char message[] =
        "psweep: stopping already: the running psim is killed and the finished rows kept\n";
    [[maybe_unused]] auto n = write(STDERR_FILENO, message, sizeof message - 1);
  } else {
    received_signal = sig;
  }
  if (wake_pipe[1] >= 0) {
    [[maybe_unused]] auto n = write(wake_pipe[1], "x", 1);
  }
  errno = saved;
}

std::vector<char*> c_strings(const std::vector<std::string>& v) {
  std::vector<char*> out;
  for (const auto& s : v) out.push_back(const_cast<char*>(s.c_str()));
  out.push_back(nullptr);
  return out;
}

void append_tail(std::string& tail, const char* data, std::size_t n) {
  tail.append(data, n);
  if (tail.size() > 2 * stderr_keep) tail.erase(0, tail.size() - stderr_keep);
}

void drain(int fd, std::string& tail) {
  char buf[4096];
  for (;;) {
    ssize_t n = read(fd, buf, sizeof buf);
    if (n > 0) {
      append_tail(tail, buf, static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    return;  // EOF, EAGAIN or error
  }
}

// The child side between fork and exec: async-signal-safe calls only.
[[noreturn]] void fail_child(const char* what) {
  const char* why = strerror(errno);  // not strictly async-signal-safe; the child exits right after
  [[maybe_unused]] auto a = write(STDERR_FILENO, what, std::strlen(what));
  [[maybe_unused]] auto b = write(STDERR_FILENO, ": ", 2);
  [[maybe_unused]] auto c = write(STDERR_FILENO, why, std::strlen(why));
  _exit(127);
}

// `fd` to the process at the other end of the socket `through` (SCM_RIGHTS). Async-signal-safe.
bool send_descriptor(int through, int fd) {
  char byte = 'f';
  iovec data{&byte, 1};
  alignas(cmsghdr) char space[CMSG_SPACE(sizeof fd)] = {};
  msghdr message{};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  message.msg_control = space;
  message.msg_controllen = sizeof space;
  cmsghdr* header = CMSG_FIRSTHDR(&message);
  header->cmsg_level = SOL_SOCKET;
  header->cmsg_type = SCM_RIGHTS;
  header->cmsg_len = CMSG_LEN(sizeof fd);
  std::memcpy(CMSG_DATA(header), &fd, sizeof fd);
  return sendmsg(through, &message, MSG_NOSIGNAL) == 1;
}

// The descriptor send_descriptor sent through `from`, or -1 when the sender ended first or
// sent nothing within `timeout_s`.
int receive_descriptor(int from, double timeout_s) {
  pollfd ready = {from, POLLIN, 0};
  int polled;
  while ((polled = poll(&ready, 1, static_cast<int>(timeout_s * 1000))) < 0 && errno == EINTR) {
  }
  if (polled <= 0) return -1;
  char byte;
  iovec data{&byte, 1};
  alignas(cmsghdr) char space[CMSG_SPACE(sizeof(int))] = {};
  msghdr message{};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  message.msg_control = space;
  message.msg_controllen = sizeof space;
  ssize_t n;
  while ((n = recvmsg(from, &message, MSG_CMSG_CLOEXEC)) < 0 && errno == EINTR) {
  }
  const cmsghdr* header = n == 1 ? CMSG_FIRSTHDR(&message) : nullptr;
  if (!header || header->cmsg_type != SCM_RIGHTS) return -1;
  int fd;
  std::memcpy(&fd, CMSG_DATA(header), sizeof fd);
  return fd;
}

// The user and CPUs of ChildIo, before anything else: a change of user clears the parent-death
// signal, so die_with_parent comes after it. With fixed CPUs, the affinity filter's listener
// goes to the parent through `keeper` and none is left here for the program to answer itself.
void become(const ChildIo& io, int err_write, int keeper) {
  if (!io.cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int cpu : io.cpus) CPU_SET(cpu, &set);
    sched_setaffinity(0, sizeof set, &set);
  }
  dup2(err_write, STDERR_FILENO);
  if (io.uid >= 0 && (setgroups(0, nullptr) != 0 || setresgid(io.gid, io.gid, io.gid) != 0 ||
                      setresuid(io.uid, io.uid, io.uid) != 0))
    fail_child("psweep: cannot change to the run's user");
  if (io.confined) {
    const int listener = supervise_affinity();
    if (listener == -1 || (listener >= 0 && !send_descriptor(keeper, listener)))
      fail_child("psweep: cannot install the seccomp filter that keeps a run on its CPUs");
    if (listener >= 0) close(listener);
    close(keeper);  // without a listener sent: the parent answers nothing
  }
  if (io.contain && !enter_containment(*io.contain))
    fail_child("psweep: cannot contain the run (the kernel refused Landlock or seccomp)");
}

[[noreturn]] void exec_child(pid_t parent, const ChildIo& io, int go_read, int go_write,
                             int err_write, int keeper, int in_fd, int out_fd,
                             const rlimit* file_size, char* const* argv, char* const* envp) {
  become(io, err_write, keeper);
  die_with_parent(parent);
  setpgid(0, 0);
  close(go_write);
  int null_fd = open("/dev/null", O_RDWR | O_CLOEXEC);  // its dup2 copies on 0 and 1 stay
  if (in_fd < 0) in_fd = null_fd;
  if (out_fd < 0) out_fd = null_fd;
  if (in_fd >= 0) dup2(in_fd, STDIN_FILENO);
  if (out_fd >= 0) dup2(out_fd, STDOUT_FILENO);
  if (file_size) setrlimit(RLIMIT_FSIZE, file_size);
  dup2(err_write, STDERR_FILENO);
  // Nothing of the grader's reaches the program but its stdin, stdout and stderr: every other
  // descriptor (runs.csv, a lock, whatever a library opened without O_CLOEXEC) closes on exec.
  // A submission once appended its own row to runs.csv through /proc/self/fd (issue 40).
  if (syscall(SYS_close_range, 3u, ~0u, CLOSE_RANGE_CLOEXEC) != 0)
    for (int fd = 3; fd < 65536; ++fd) fcntl(fd, F_SETFD, FD_CLOEXEC);
  char go;
  while (read(go_read, &go, 1) < 0 && errno == EINTR) {
  }
  execve(argv[0], argv, envp);
  const char* msg = "psweep: cannot execute ";
  [[maybe_unused]] auto a = write(STDERR_FILENO, msg, std::strlen(msg));
  fail_child(argv[0]);
}

}  // namespace

void die_with_parent(pid_t parent) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(128 + SIGKILL);
}

void install_interrupt_handlers() {
  if (wake_pipe[0] < 0 && pipe2(wake_pipe, O_CLOEXEC | O_NONBLOCK) != 0)
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  struct sigaction sa;
  std::memset(&sa, 0, sizeof sa);
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int interrupt_signal() { return received_signal; }

namespace {

// A file for the child's stdin or stdout, opened by the parent (whose errors it can report);
// closed on exec, after the child has duplicated it.
class ChildFile {
 public:
  ChildFile(const std::string& path, int flags) {
    if (path.empty()) return;
    fd_ = open(path.c_str(), flags | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw std::runtime_error(fmt::format("cannot open {}: {}", path, std::strerror(errno)));
  }
  explicit ChildFile(int fd) : fd_(fd) {}
  ~ChildFile() {
    if (fd_ >= 0) close(fd_);
  }
  ChildFile(const ChildFile&) = delete;
  ChildFile& operator=(const ChildFile&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

// The child's stdin: a private, sealed in-memory copy of the scene, so that a program can neither
// change the file that later runs and checks read (through /proc/self/fd/0, as the grader's own
// user) nor its own input; -1 for none.
int sealed_copy(const std::string& path) {
  if (path.empty()) return -1;
  const ChildFile source(path, O_RDONLY);
  struct stat st {};
  const int fd = memfd_create("scene", MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (fd < 0 || fstat(source.fd(), &st) != 0) {
    if (fd >= 0) close(fd);
    throw std::runtime_error(fmt::format("cannot copy {}: {}", path, std::strerror(errno)));
  }
  for (off_t at = 0; at < st.st_size;) {
    const ssize_t n = sendfile(fd, source.fd(), &at, static_cast<std::size_t>(st.st_size - at));
    if (n > 0) continue;
    if (n < 0 && errno == EINTR) continue;
    const int why = n < 0 ? errno : EIO;
    close(fd);
    throw std::runtime_error(fmt::format("cannot copy {}: {}", path, std::strerror(why)));
  }
  fcntl(fd, F_ADD_SEALS, F_SEAL_WRITE | F_SEAL_GROW | F_SEAL_SHRINK | F_SEAL_SEAL);
  lseek(fd, 0, SEEK_SET);
  return fd;
}

// Every descendant of `pid` as a pidfd, read from /proc/P/task/T/children: those in another
// process group or session (setsid) that kill(-pid) misses, and a sandbox's init, whose
// namespace the kernel tears down only as it exits.
std::vector<int> descendant_pidfds(pid_t pid) {
  std::vector<int> fds;
  std::vector<pid_t> todo = {pid};
  while (!todo.empty() && fds.size() < 4096) {
    const pid_t p = todo.back();
    todo.pop_back();
    std::error_code ec;
    for (const auto& task :
         std::filesystem::directory_iterator("/proc/" + std::to_string(p) + "/task", ec)) {
      std::ifstream children(task.path() / "children");
      for (pid_t child; children >> child;) {
        const int fd = static_cast<int>(syscall(SYS_pidfd_open, child, 0));
        if (fd >= 0) fds.push_back(fd);
        todo.push_back(child);
      }
    }
  }
  return fds;
}

// Waits until each pidfd's process has exited (at most 2 s in all), then closes them: so that
// nothing of a killed run is alive when its row is written.
void await_exits(const std::vector<int>& fds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  for (int fd : fds) {
    pollfd p = {fd, POLLIN, 0};
    for (;;) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          until - std::chrono::steady_clock::now());
      if (left.count() <= 0 || poll(&p, 1, static_cast<int>(left.count())) >= 0) break;
      if (errno != EINTR) break;
    }
    close(fd);
  }
}

}  // namespace

namespace {

// The handshake and stderr pipes, close-on-exec; none left open when the second fails.
void open_pipes(int go[2], int err[2]) {
  if (pipe2(go, O_CLOEXEC) != 0)
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  if (pipe2(err, O_CLOEXEC) != 0) {
    close(go[0]);
    close(go[1]);
    throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  }
}

// What watch() did: killed the tree (at the deadline or an interrupt), whose pidfds it keeps.
struct Watched {
  bool killed = false;
  std::vector<int> descendants;
};

// The parent's side while the child runs, until it exits: its stderr into the result's tail,
// and at the deadline, on SIGINT/SIGTERM or when its folder is over its limit the whole tree
// killed (its process group, and by pidfd the descendants that left it), the outcome set
// accordingly.
Watched watch(pid_t pid, int pidfd, int err_fd, AffinityKeeper* keeper, const FolderLimit& folder,
              std::chrono::steady_clock::time_point deadline, ChildResult& result) {
  Watched w;
  bool err_open = true;
  int keeper_fd = keeper ? keeper->fd() : -1;
  const auto poll_every = std::chrono::milliseconds(kFolderPollMs);
  auto next_poll = std::chrono::steady_clock::now() + poll_every;
  for (;;) {
    if (!w.killed) {
      const auto now = std::chrono::steady_clock::now();
      const bool late = now >= deadline;
      std::optional<std::string> over;
      if (!folder.path.empty() && now >= next_poll) {
        over = over_limit(folder);
        next_poll = now + poll_every;
      }
      if (late || received_signal || over) {
        result.outcome = over ? Outcome::over_limit
                              : late ? Outcome::timed_out : Outcome::interrupted;
        if (over) result.over = *over;
        w.descendants = descendant_pidfds(pid);
        kill(-pid, SIGKILL);
        for (int fd : w.descendants) syscall(SYS_pidfd_send_signal, fd, SIGKILL, nullptr, 0);
        w.killed = true;
      }
    }
    siginfo_t info;
    info.si_pid = 0;
    if (waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
        info.si_pid == pid)
      return w;
    auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    int wait_ms = w.killed ? 50
                           : static_cast<int>(std::clamp<long long>(
                                 left.count() + 1, 0, folder.path.empty() ? 1000 : kFolderPollMs));
    if (pidfd < 0) wait_ms = std::min(wait_ms, 10);  // no pidfd (kernel < 5.3): short polls
    pollfd fds[4] = {{pidfd, POLLIN, 0},
                     {err_open ? err_fd : -1, POLLIN, 0},
                     {wake_pipe[0], POLLIN, 0},
                     {keeper_fd, POLLIN, 0}};
    if (poll(fds, 4, wait_ms) < 0 && errno != EINTR) return w;
    if (fds[3].revents & POLLIN)
      keeper->answer();
    else if (fds[3].revents)
      keeper_fd = -1;  // every process of the run has ended
    if (fds[1].revents) {
      char buf[4096];
      ssize_t n = read(err_fd, buf, sizeof buf);
      if (n > 0)
        append_tail(result.stderr_tail, buf, static_cast<std::size_t>(n));
      else if (n == 0 || (errno != EAGAIN && errno != EINTR))
        err_open = false;
    }
    if (fds[2].revents) {
      char buf[64];
      while (read(wake_pipe[0], buf, sizeof buf) > 0) {
      }
    }
  }
}

// psweep's own children: where it is a subreaper (run/contain.hpp), a run's orphans among them.
std::vector<pid_t> own_children() {
  std::vector<pid_t> pids;
  std::error_code ec;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", ec)) {
    std::ifstream children(task.path() / "children");
    for (pid_t child; children >> child;) pids.push_back(child);
  }
  return pids;
}

// `more`'s times added to `usage`, the larger peak kept: as the kernel sums reaped children.
void add_usage(rusage& usage, const rusage& more) {
  timeradd(&usage.ru_utime, &more.ru_utime, &usage.ru_utime);
  timeradd(&usage.ru_stime, &more.ru_stime, &usage.ru_stime);
  usage.ru_maxrss = std::max(usage.ru_maxrss, more.ru_maxrss);
}

// Every process a confined run left behind (its process group, and the orphans that came to
// psweep, with their descendants), killed and reaped, their rusage added to `usage`: nothing of a
// run outlives its row, and a bwrap sandbox's init, which exits after bwrap and holds the
// program's rusage (bwrap does not reap it), is counted.
void kill_leftovers(pid_t pid, const std::vector<pid_t>& before, rusage& usage) {
  kill(-pid, SIGKILL);
  std::vector<int> fds;
  // Until no orphan is left: a chain of setsid-fork-and-exit hands its next link to psweep after
  // a round's listing (two of six such chains once outlived a grading, issue 57). Each round
  // kills every process listed, so only what one forked before its kill comes to the next.
  for (int round = 0; round < 1000; ++round) {
    bool any = false;
    for (pid_t child : own_children()) {
      if (std::find(before.begin(), before.end(), child) != before.end()) continue;
      any = true;
      for (int fd : descendant_pidfds(child)) fds.push_back(fd);
      kill(child, SIGKILL);
      for (int fd : fds) syscall(SYS_pidfd_send_signal, fd, SIGKILL, nullptr, 0);
      rusage theirs{};
      while (wait4(child, nullptr, 0, &theirs) < 0 && errno == EINTR) {
      }
      add_usage(usage, theirs);
    }
    if (!any) break;
  }
  await_exits(fds);
}

// How a child that was not killed ended, from wait4's status.
void set_ending(ChildResult& result, int status) {
  if (WIFSIGNALED(status)) {
    result.outcome = Outcome::signaled;
    result.signal = WTERMSIG(status);
  } else {
    result.outcome = Outcome::exited;
    result.exit_code = WEXITSTATUS(status);
  }
}

}  // namespace

ChildResult run_child(const std::vector<std::string>& argv_s, const std::vector<std::string>& env_s,
                      double timeout_s, const CounterAvailability* counters, const ChildIo& io) {
  auto argv = c_strings(argv_s);
  auto envp = c_strings(env_s);
  const ChildFile in(sealed_copy(io.stdin_path));
  const ChildFile out(io.stdout_path, O_WRONLY | O_CREAT | O_TRUNC);
  const rlimit file_size{io.file_size_limit, io.file_size_limit};
  int go[2], err[2];
  open_pipes(go, err);
  // The affinity filter's listener comes back from the child through this pair.
  int keeper_pair[2] = {-1, -1};
  if (io.confined && socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, keeper_pair) != 0) {
    for (int fd : {go[0], go[1], err[0], err[1]}) close(fd);
    throw std::runtime_error(std::string("socketpair: ") + std::strerror(errno));
  }

  ChildResult result;
  ChildCounters perf;
  const auto start = std::chrono::steady_clock::now();
  const pid_t self = getpid();
  if (io.confined) prctl(PR_SET_CHILD_SUBREAPER, 1);
  const std::vector<pid_t> before = io.confined ? own_children() : std::vector<pid_t>{};
  pid_t pid = fork();
  if (pid < 0) {
    for (int fd : {go[0], go[1], err[0], err[1], keeper_pair[0], keeper_pair[1]})
      if (fd >= 0) close(fd);
    throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  }
  if (pid == 0)
    exec_child(self, io, go[0], go[1], err[1], keeper_pair[1], in.fd(), out.fd(),
               io.file_size_limit ? &file_size : nullptr, argv.data(), envp.data());

  setpgid(pid, pid);  // also in the child: whichever runs first, the group exists before exec
  close(go[0]);
  close(err[1]);
  std::optional<AffinityKeeper> keeper;
  if (io.confined) {
    close(keeper_pair[1]);
    // None when the child failed before sending it (it says why on stderr and exits), or sends
    // none (run/seccomp.hpp, kNoSupervisor), or hangs before (the deadline kills it).
    if (const int listener = receive_descriptor(keeper_pair[0], timeout_s); listener >= 0)
      keeper.emplace(listener, io.cpus);
    close(keeper_pair[0]);
  }
  if (counters) perf.open(pid, *counters);
  [[maybe_unused]] auto w = write(go[1], "g", 1);
  close(go[1]);
  fcntl(err[0], F_SETFL, O_NONBLOCK);
  int pidfd = static_cast<int>(syscall(SYS_pidfd_open, pid, 0));

  const Watched watched =
      watch(pid, pidfd, err[0], keeper ? &*keeper : nullptr, io.folder,
            start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                        std::chrono::duration<double>(timeout_s)),
            result);
  int status = 0;
  while (wait4(pid, &status, 0, &result.usage) < 0 && errno == EINTR) {
  }
  result.process_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (io.confined) kill_leftovers(pid, before, result.usage);
  if (io.confined && io.own_user) {  // what left psweep's sight: killed, then reaped here
    kill_every_process_of(io.uid, io.gid);
    kill_leftovers(pid, before, result.usage);
  }
  if (watched.killed) {
    kill(-pid, SIGKILL);  // descendants that outlived the leader
    await_exits(watched.descendants);
  } else {
    set_ending(result, status);
  }
  drain(err[0], result.stderr_tail);
  close(err[0]);
  if (pidfd >= 0) close(pidfd);
  if (result.stderr_tail.size() > stderr_keep)
    result.stderr_tail.erase(0, result.stderr_tail.size() - stderr_keep);
  if (counters) result.events = perf.read();
  return result;
}

}  // namespace psweep

#include <spawn.h>

extern char** environ;

namespace psweep {

std::optional<std::string> capture_output(const std::vector<std::string>& argv_s) {
  auto argv = c_strings(argv_s);
  int out[2];
  if (pipe2(out, O_CLOEXEC) != 0) return std::nullopt;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addclosefrom_np(&actions, 3);
  pid_t pid;
  int rc = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(out[1]);
  if (rc != 0) {
    close(out[0]);
    return std::nullopt;
  }
  std::string text;
  char buf[4096];
  for (;;) {
    ssize_t n = read(out[0], buf, sizeof buf);
    if (n > 0)
      text.append(buf, static_cast<std::size_t>(n));
    else if (n < 0 && errno == EINTR)
      continue;
    else
      break;
  }
  close(out[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return std::nullopt;
  return text;
}

}  // namespace psweep
