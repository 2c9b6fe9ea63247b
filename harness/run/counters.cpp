#include "run/counters.hpp"

#include <fmt/format.h>
#include <linux/perf_event.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace psweep {
namespace {

struct EventSpec {
  std::uint32_t type;
  std::uint64_t config;
};

// Table order = the order ChildCounters::read() unpacks them.
constexpr EventSpec events[] = {
    {PERF_TYPE_SOFTWARE, PERF_COUNT_SW_TASK_CLOCK},
    {PERF_TYPE_SOFTWARE, PERF_COUNT_SW_CONTEXT_SWITCHES},
    {PERF_TYPE_SOFTWARE, PERF_COUNT_SW_CPU_MIGRATIONS},
    {PERF_TYPE_SOFTWARE, PERF_COUNT_SW_PAGE_FAULTS},
    {PERF_TYPE_HARDWARE, PERF_COUNT_HW_CPU_CYCLES},
    {PERF_TYPE_HARDWARE, PERF_COUNT_HW_INSTRUCTIONS},
    {PERF_TYPE_HARDWARE, PERF_COUNT_HW_BRANCH_INSTRUCTIONS},
    {PERF_TYPE_HARDWARE, PERF_COUNT_HW_BRANCH_MISSES},
    {PERF_TYPE_HARDWARE, PERF_COUNT_HW_CACHE_MISSES},
};

int open_event(const EventSpec& e, pid_t pid, bool user_only, bool on_exec) {
  perf_event_attr attr;
  std::memset(&attr, 0, sizeof attr);
  attr.size = sizeof attr;
  attr.type = e.type;
  attr.config = e.config;
  attr.read_format = PERF_FORMAT_TOTAL_TIME_ENABLED | PERF_FORMAT_TOTAL_TIME_RUNNING;
  attr.inherit = 1;
  attr.exclude_hv = 1;
  attr.exclude_kernel = user_only ? 1 : 0;
  attr.disabled = on_exec ? 1 : 0;
  attr.enable_on_exec = on_exec ? 1 : 0;
  return static_cast<int>(syscall(SYS_perf_event_open, &attr, pid, -1, -1, PERF_FLAG_FD_CLOEXEC));
}

// Tries the event on the harness itself: with the kernel included first, then user-only.
bool probe(const EventSpec& e, bool& user_only, std::string& why) {
  for (bool user : {false, true}) {
    int fd = open_event(e, 0, user, false);
    if (fd >= 0) {
      close(fd);
      user_only = user;
      return true;
    }
    why = std::strerror(errno);
    if (errno != EACCES && errno != EPERM) break;  // paranoia is the only thing user-only fixes
  }
  return false;
}

}  // namespace

CounterAvailability probe_counters() {
  CounterAvailability a;
  std::string sw_why, hw_why;
  bool hw_user_only = false;
  a.software = probe(events[0], a.user_only, sw_why);
  a.hardware = probe(events[4], hw_user_only, hw_why);
  if (a.software && a.hardware) a.user_only = a.user_only || hw_user_only;
  a.note =
      a.software
          ? fmt::format("software perf events available{}", a.user_only ? " (user space only)" : "")
          : fmt::format(
                "software perf events unavailable (perf_event_open: {}): context_switches = "
                "voluntary + "
                "involuntary and page_faults = minor + major from rusage; task_clock_s and "
                "cpu_migrations empty",
                sw_why);
  a.note += a.hardware ? "; hardware perf events available"
                       : fmt::format(
                             "; hardware perf events unavailable (perf_event_open: {}): cycles, "
                             "instructions, branches, "
                             "branch_misses and cache_misses are empty",
                             hw_why);
  return a;
}

ChildCounters::~ChildCounters() {
  for (int fd : fds_)
    if (fd >= 0) close(fd);
}

void ChildCounters::open(pid_t child, const CounterAvailability& a) {
  fds_.assign(std::size(events), -1);
  for (std::size_t i = 0; i < std::size(events); ++i) {
    bool hardware = events[i].type == PERF_TYPE_HARDWARE;
    if (hardware ? a.hardware : a.software)
      fds_[i] = open_event(events[i], child, a.user_only, true);
  }
}

EventCounts ChildCounters::read() const {
  std::optional<std::uint64_t> value[std::size(events)];
  for (std::size_t i = 0; i < fds_.size(); ++i) {
    std::uint64_t buf[3];  // value, time_enabled, time_running
    if (fds_[i] < 0 || ::read(fds_[i], buf, sizeof buf) != static_cast<ssize_t>(sizeof buf))
      continue;
    if (buf[2] == 0) {  // never scheduled on a counter: unknown, not zero
      if (buf[1] == 0 && events[i].type == PERF_TYPE_SOFTWARE) value[i] = 0;
      continue;
    }
    value[i] = buf[2] < buf[1]
                   ? static_cast<std::uint64_t>(static_cast<double>(buf[0]) * buf[1] / buf[2])
                   : buf[0];
  }
  EventCounts c;
  if (value[0])
    c.task_clock_s = static_cast<double>(*value[0]) / 1e9;  // task-clock counts nanoseconds
  c.context_switches = value[1];
  c.cpu_migrations = value[2];
  c.page_faults = value[3];
  c.cycles = value[4];
  c.instructions = value[5];
  c.branches = value[6];
  c.branch_misses = value[7];
  c.cache_misses = value[8];
  return c;
}

}  // namespace psweep
