// Containment: see contain.hpp.
#include "run/contain.hpp"

#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>

#include "run/confine.hpp"
#include "run/run_user.hpp"
#include "run/seccomp.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

// What every run may read: the system's programs and libraries, and what runtimes look up.
const std::vector<std::string> kReadable = {"/usr",   "/etc",   "/bin",  "/sbin", "/lib",
                                            "/lib64", "/lib32", "/proc", "/sys",  "/dev"};
const std::vector<std::string> kDevices = {"/dev/null", "/dev/zero"};

// The threads the run's user already has, which RLIMIT_NPROC counts with the run's: none for a
// user of its own (run/run_user.hpp); psweep's user's where it is not root.
rlim_t threads_of(uid_t uid) {
  rlim_t n = 0;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    struct stat st {};
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos ||
        stat(entry.path().c_str(), &st) != 0 || st.st_uid != uid)
      continue;
    for (auto task = fs::directory_iterator(entry.path() / "task", ec);
         !ec && task != fs::directory_iterator(); task.increment(ec))
      ++n;
  }
  return n;
}

// `others`: the threads of the run's user that RLIMIT_NPROC counts besides the run's.
std::vector<std::pair<int, rlimit>> limits_of(const Limits& limits, double cpu_s, int threads,
                                              rlim_t others) {
  const auto mib = [](std::int64_t m) { return static_cast<rlim_t>(m) << 20; };
  const auto cpu = static_cast<rlim_t>(std::ceil(cpu_s));
  const rlim_t processes = static_cast<rlim_t>(limits.processes) + others;
  return {{RLIMIT_CPU, {cpu, cpu + 1}},
          {RLIMIT_DATA, {mib(limits.memory_mib), mib(limits.memory_mib)}},
          {RLIMIT_AS,
           {mib(address_space_mib(limits.memory_mib, threads)),
            mib(address_space_mib(limits.memory_mib, threads))}},
          {RLIMIT_STACK, {kStackBytes, kStackBytes}},
          {RLIMIT_NPROC, {processes, processes}},
          {RLIMIT_NOFILE,
           {static_cast<rlim_t>(limits.open_files), static_cast<rlim_t>(limits.open_files)}},
          {RLIMIT_CORE, {0, 0}}};
}

class ContainedTier : public Tier {
 public:
  explicit ContainedTier(int abi) : abi_(abi) {}
  std::string name() const override { return "landlock+seccomp"; }

  ChildResult run(const Program& program, const std::vector<std::string>& argv,
                  const std::vector<std::string>& env, double timeout_s, int threads,
                  std::uint64_t file_bytes, ChildIo io,
                  const CounterAvailability* counters) override {
    std::vector<std::string> words = argv;
    std::vector<std::string> readable = kReadable;
    for (const std::string& copy : stage_words(words, stage_)) readable.push_back(copy);
    Containment c;
    c.folder = stage_.fresh_folder(io.uid, io.gid);
    const PathRules paths(readable, kDevices, {c.folder});
    c.paths = &paths;
    c.landlock_abi = abi_;
    // A user of its own has no thread left by then (run/run_user.hpp): no /proc walk per run.
    c.limits = limits_of(program.limits, cpu_seconds(program.limits, timeout_s, threads), threads,
                         io.own_user ? 0
                                     : threads_of(io.uid >= 0 ? static_cast<uid_t>(io.uid)
                                                              : geteuid()));
    io.file_size_limit = file_bytes;
    io.contain = &c;
    io.folder = {c.folder, static_cast<std::uint64_t>(program.limits.disk_mib) << 20,
                 static_cast<std::uint64_t>(folder_files(program.limits)),
                 fmt::format("disk_mib = {} MiB", program.limits.disk_mib)};
    std::vector<std::string> inside = {"PATH=/usr/local/bin:/usr/bin:/bin", "HOME=" + c.folder,
                                       "TMPDIR=" + c.folder};
    inside.insert(inside.end(), env.begin(), env.end());
    ChildResult result = run_child(words, inside, timeout_s, counters, io);
    std::error_code ec;
    fs::remove_all(c.folder, ec);
    return result;
  }

  double start_s() override {
    Program none;
    double best = 0;
    for (int i = 0; i < 5; ++i) {
      ChildIo io;
      io.confined = true;  // as every run: its filter, its reaper and its user's end counted
      run_as_own_user_if_root(io);
      const double s = run(none, {"/bin/true"}, {}, 10, 1, 0, io, nullptr).process_s;
      best = i == 0 ? s : std::min(best, s);
    }
    return best;
  }

 private:
  int abi_;
  Stage stage_;
};

}  // namespace

bool enter_containment(const Containment& c) {
  if (chdir(c.folder.c_str()) != 0) return false;
  for (const auto& [resource, limit] : c.limits)
    if (setrlimit(static_cast<__rlimit_resource>(resource), &limit) != 0) return false;
  return restrict_to(*c.paths, c.landlock_abi) && forbid_escapes();
}

std::unique_ptr<Tier> contained_tier(std::string& why) {
  const int abi = landlock_abi();
  if (abi < 1) {
    why = "the kernel offers no Landlock (or a seccomp policy refuses it)";
    return nullptr;
  }
  return std::make_unique<ContainedTier>(abi);
}

}  // namespace psweep
