// Confinement: see confine.hpp.
#include "run/confine.hpp"

#include <elf.h>
#include <fmt/format.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "config/program.hpp"
#include "run/record.hpp"
#include "run/run_user.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

constexpr const char* kFolder = "/box";  // the run's working folder and HOME, inside
constexpr const char* kPrograms = "/program";

// The host's folders a sandbox shows, read-only: programs, libraries, the loader's cache.
bool system_path(const std::string& path) {
  for (const char* root : {"/usr/", "/etc/", "/bin/", "/sbin/", "/lib/", "/lib64/", "/lib32/"})
    if (path.rfind(root, 0) == 0) return true;
  return false;
}

std::string mib_bytes(std::int64_t mib) { return fmt::format("{}", mib << 20); }

// A sandbox's tools, found on PATH (a name without '/' where they are not).
SandboxSpec with_tools() {
  SandboxSpec spec;
  spec.bwrap = resolve_executable("bwrap");
  spec.prlimit = resolve_executable("prlimit");
  return spec;
}

}  // namespace

std::int64_t folder_files(const Limits& limits) { return limits.disk_mib * 256; }

std::int64_t address_space_mib(std::int64_t memory_mib, int threads) {
  return memory_mib + 512 + 128 * std::max(threads, 1);
}

Stage::Stage() {
  // A psweep killed outright leaves its stage: the next one clears those of dead processes.
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("psweep-stage-", 0) != 0) continue;
    const long pid = std::strtol(name.c_str() + 13, nullptr, 10);
    if (pid > 0 && kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH)
      fs::remove_all(entry.path(), ec);
  }
  std::string pattern =
      (fs::temp_directory_path() / fmt::format("psweep-stage-{}-XXXXXX", getpid())).string();
  if (!mkdtemp(pattern.data()))
    throw std::runtime_error(fmt::format("cannot make a stage folder in {}: {}",
                                         fs::temp_directory_path().string(), std::strerror(errno)));
  folder_ = pattern;
  // Others may pass through, not list: each run's user reaches only the paths it is given.
  fs::permissions(folder_, fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
}

Stage::~Stage() {
  std::error_code ec;
  fs::remove_all(folder_, ec);
}

std::string Stage::fresh_folder(int uid, int gid) {
  std::string pattern = (fs::path(folder_) / "run-XXXXXX").string();
  if (!mkdtemp(pattern.data()) || (uid >= 0 && chown(pattern.c_str(), uid, gid) != 0))
    throw std::runtime_error(
        fmt::format("cannot make a run's folder in {}: {}", folder_, std::strerror(errno)));
  return pattern;
}

std::string Stage::add(const std::string& path) {
  const std::string source = fs::canonical(path).string();
  if (auto at = copies_.find(source); at != copies_.end()) return at->second;
  const fs::path dir = fs::path(folder_) / std::to_string(copies_.size());
  fs::create_directory(dir);
  fs::permissions(dir, fs::perms::owner_all | fs::perms::group_exec | fs::perms::others_exec);
  const fs::path copy = dir / fs::path(source).filename();
  fs::copy_file(source, copy);
  const bool executable =
      (fs::status(source).permissions() & fs::perms::owner_exec) != fs::perms::none;
  fs::permissions(
      copy, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read |
                (executable ? fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec
                            : fs::perms::none));
  return copies_[source] = copy.string();
}

Confined sandbox_command(const SandboxSpec& spec, const std::vector<std::string>& program_argv) {
  std::vector<std::string> a = {
      spec.bwrap, "--unshare-all", "--die-with-parent", "--new-session", "--ro-bind",
      "/usr",     "/usr",          "--ro-bind",         "/etc",          "/etc"};
  // /bin, /lib, ...: links into /usr on a merged /usr (Debian 12), folders elsewhere.
  for (const char* top : {"/bin", "/sbin", "/lib", "/lib64", "/lib32"}) {
    std::error_code ec;
    if (fs::is_symlink(top, ec))
      a.insert(a.end(), {"--symlink", fs::read_symlink(top, ec).string(), top});
    else if (fs::is_directory(top, ec))
      a.insert(a.end(), {"--ro-bind", top, top});
  }
  for (const std::string& folder : spec.hide)
    if (system_path(folder + "/")) a.insert(a.end(), {"--tmpfs", folder});
  // /dev read-only: bwrap's /dev is a tmpfs of half the machine's memory. /sys read-only, as
  // the other tier's Landlock allows it: hwloc reads the CPUs' topology there, and OpenMPI's
  // mpirun (a program's own launcher, {P}) stops with "topology discovery failed" without it.
  a.insert(a.end(), {"--proc", "/proc", "--ro-bind", "/sys", "/sys", "--dev", "/dev",
                     "--remount-ro", "/dev", "--dir", "/tmp", "--dir", kFolder});
  for (const auto& [host, inside] : spec.files) a.insert(a.end(), {"--ro-bind", host, inside});
  // bwrap's root is a tmpfs of half the machine's memory, writable by the program.
  a.insert(a.end(), {"--remount-ro", "/"});
  // The writable folders, mounted inside by the sandbox's root with both a size and a number of
  // files (bwrap's --size has no inode count: a million empty files in /box held 864 MB of kernel
  // memory, issue 40); then every capability dropped, for good, before prlimit and the program.
  const std::string options =
      fmt::format("size={},nr_inodes={}", mib_bytes(spec.limits.disk_mib), folder_files(spec.limits));
  a.insert(a.end(),
           {"--uid", "0", "--gid", "0", "--cap-add", "CAP_SYS_ADMIN", "--cap-add", "CAP_SETPCAP",
            "--chdir", "/", "--", "/bin/sh", "-c",
            fmt::format("set -e; for d in /tmp /dev/shm {0}; do mount -t tmpfs -o {1},mode=1777 "
                        "tmpfs $d; done; cd {0}; exec setpriv --inh-caps=-all --ambient-caps=-all "
                        "--bounding-set=-all -- \"$@\"",
                        kFolder, options),
            "sandbox"});
  const auto cpu = static_cast<long long>(std::ceil(spec.cpu_s));
  a.insert(a.end(),
           {spec.prlimit,
            // SIGXCPU at the soft limit says why; SIGKILL a second later if ignored
            fmt::format("--cpu={}:{}", cpu, cpu + 1), "--data=" + mib_bytes(spec.limits.memory_mib),
            "--as=" + mib_bytes(address_space_mib(spec.limits.memory_mib, spec.threads)),
            fmt::format("--stack={0}:{0}", kStackBytes),
            fmt::format("--nproc={}", spec.limits.processes),
            fmt::format("--nofile={}", spec.limits.open_files), "--core=0"});
  if (spec.file_bytes) a.push_back(fmt::format("--fsize={}", spec.file_bytes));
  a.push_back("--");
  a.insert(a.end(), program_argv.begin(), program_argv.end());
  std::vector<std::string> env = {"PATH=/usr/local/bin:/usr/bin:/bin",
                                  fmt::format("HOME={}", kFolder)};
  env.insert(env.end(), spec.env.begin(), spec.env.end());
  return {std::move(a), std::move(env)};
}

Confined confine(const Program& program, const std::vector<std::string>& argv,
                 const std::vector<std::string>& env, double timeout_s, int cpus,
                 std::uint64_t file_bytes, const std::vector<std::string>& hide, Stage& stage) {
  SandboxSpec spec = with_tools();
  spec.limits = program.limits;
  spec.cpu_s = cpu_seconds(program.limits, timeout_s, cpus);
  spec.file_bytes = file_bytes;
  spec.threads = cpus;
  spec.hide = hide;
  spec.env = env;
  std::vector<std::string> inside = argv;
  // The program at /program/NAME, the files it names in folders of their own.
  for (const std::string& copy : stage_words(inside, stage)) {
    const std::string name = fs::path(copy).filename().string();
    const std::string at = spec.files.empty()
                               ? fmt::format("{}/{}", kPrograms, name)
                               : fmt::format("{}/{}/{}", kPrograms, spec.files.size(), name);
    std::replace(inside.begin(), inside.end(), copy, at);
    spec.files.emplace_back(copy, at);
  }
  return sandbox_command(spec, inside);
}

std::vector<std::string> stage_words(std::vector<std::string>& argv, Stage& stage) {
  std::vector<std::string> copies;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    std::error_code ec;
    if (i > 0 && !fs::is_regular_file(argv[i], ec)) continue;
    const std::string real = fs::canonical(argv[i], ec).string();
    if (ec || system_path(real)) continue;  // argv[0] from /usr, or a plain argument
    argv[i] = stage.add(real);
    if (std::find(copies.begin(), copies.end(), argv[i]) == copies.end()) copies.push_back(argv[i]);
  }
  return copies;
}

double cpu_seconds(const Limits& limits, double timeout_s, int cpus) {
  return limits.cpu_s > 0 ? limits.cpu_s : timeout_s * std::max(cpus, 1);
}

namespace {

// A 16-bit field of an ELF header, little-endian on every machine this lab builds for.
int elf_half(const std::string& head, std::size_t at) {
  return static_cast<unsigned char>(head[at]) | static_cast<unsigned char>(head[at + 1]) << 8;
}

// The machine an ELF header (at least its first 20 bytes) is for: e_machine.
int elf_machine(const std::string& head) { return head.size() < 20 ? -1 : elf_half(head, 18); }

std::string machine_name(int machine) {
  switch (machine) {
    case EM_X86_64:
      return "x86-64";
    case EM_386:
      return "32-bit x86";
    case EM_AARCH64:
      return "AArch64 (arm64)";
    case EM_ARM:
      return "32-bit ARM";
    case EM_RISCV:
      return "RISC-V";
    case EM_PPC64:
      return "64-bit PowerPC";
    default:
      return fmt::format("ELF machine {}", machine);
  }
}

// Why an ELF file cannot run here: another machine's, not a linked program, or cut short.
std::optional<std::string> elf_problem(const std::string& head) {
  static const int here = [] {
    char bytes[20] = {};
    std::ifstream self("/proc/self/exe", std::ios::binary);
    self.read(bytes, sizeof bytes);
    return elf_machine(std::string(bytes, sizeof bytes));
  }();
  const int machine = elf_machine(head);
  if (machine < 0) return "an ELF file cut short (fewer than 20 bytes): not a program";
  if (machine != here)
    return fmt::format("a program for {}, and this machine is {}: build it here",
                       machine_name(machine), machine_name(here));
  const int type = elf_half(head, 16);  // e_type
  if (type != ET_EXEC && type != ET_DYN)
    return "an ELF object file, not a linked program: link it (g++ -o NAME ...)";
  return std::nullopt;
}

}  // namespace

std::optional<std::string> cannot_execute(const std::string& path) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status))
    return path.find('/') == std::string::npos ? "not found on PATH" : std::strerror(ENOENT);
  if (fs::is_directory(status)) return std::strerror(EISDIR);
  if ((status.permissions() &
       (fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec)) == fs::perms::none)
    return fmt::format("{} (not executable: chmod +x it)", std::strerror(EACCES));
  char bytes[256] = {};  // the kernel reads as much of a #! line
  std::ifstream in(path, std::ios::binary);
  in.read(bytes, sizeof bytes);
  const std::string head(bytes, static_cast<std::size_t>(in.gcount()));
  if (head.rfind("\x7f"
                 "ELF",
                 0) == 0)
    return elf_problem(head);
  // A sandbox's execvp runs any other file with /bin/sh: an ELF for another machine once failed
  // as `Syntax error: "(" unexpected`.
  if (head.rfind("#!", 0) != 0)
    return "neither a program (ELF) nor a script with a #! line: add one, such as #!/bin/sh";
  const std::string first = head.substr(0, head.find('\n'));
  if (first.back() == '\r')
    return "its #! line ends in a carriage return (Windows line endings, CR LF), so the system "
           "looks for an interpreter whose name ends in \\r: convert the file with dos2unix";
  const std::size_t start = first.find_first_not_of(" \t", 2);
  if (start == std::string::npos) return "its #! line names no interpreter";
  std::string interpreter = first.substr(start, first.find_first_of(" \t\r", start) - start);
  if (!fs::exists(interpreter, ec))
    return fmt::format("its interpreter {} (the #! line) does not exist", interpreter);
  if (!system_path(fs::canonical(interpreter, ec).string()))
    return fmt::format(
        "its interpreter {} (the #! line) is not under /usr, so the sandbox "
        "has none",
        interpreter);
  return std::nullopt;
}

namespace {

// A sandbox that runs `true`, and how a run of it ended.
ChildResult run_empty_sandbox() {
  SandboxSpec spec = with_tools();
  spec.cpu_s = 10;
  const Confined probe = sandbox_command(spec, {"/bin/true"});
  ChildIo io;
  io.confined = true;  // as every run: its filter, its reaper and its user's end counted
  run_as_own_user_if_root(io);
  return run_child(probe.argv, probe.env, 10, nullptr, io);
}

}  // namespace

double sandbox_start_s() {
  double best = 0;
  for (int i = 0; i < 5; ++i) {
    const double s = run_empty_sandbox().process_s;
    best = i == 0 ? s : std::min(best, s);
  }
  return best;
}

namespace {

// bwrap exits 128 + n when the program died of signal n, as a shell does: read it back as the
// signal (a program that exits 139 itself reads as a crash too, as it would under a shell).
ChildResult as_signal(ChildResult r) {
  if (r.outcome == Outcome::exited && r.exit_code > 128 && r.exit_code < 128 + 65) {
    r.outcome = Outcome::signaled;
    r.signal = r.exit_code - 128;
  }
  return r;
}

class BwrapTier : public Tier {
 public:
  explicit BwrapTier(std::vector<std::string> hide) : hide_(std::move(hide)) {}
  std::string name() const override { return "bwrap"; }
  ChildResult run(const Program& program, const std::vector<std::string>& argv,
                  const std::vector<std::string>& env, double timeout_s, int threads,
                  std::uint64_t file_bytes, ChildIo io,
                  const CounterAvailability* counters) override {
    const Confined c = confine(program, argv, env, timeout_s, threads, file_bytes, hide_, stage_);
    return as_signal(run_child(c.argv, c.env, timeout_s, counters, io));
  }
  double start_s() override { return sandbox_start_s(); }

 private:
  std::vector<std::string> hide_;
  Stage stage_;
};

}  // namespace

std::unique_ptr<Tier> bwrap_tier(const std::vector<std::string>& hide, std::string& why) {
  if (auto problem = confinement_problem()) {
    why = *problem;
    return nullptr;
  }
  return std::make_unique<BwrapTier>(hide);
}

std::optional<std::string> confinement_problem() {
  const SandboxSpec spec = with_tools();
  if (spec.bwrap.find('/') == std::string::npos)
    return "bubblewrap (bwrap) is not installed: apt-get install bubblewrap";
  if (spec.prlimit.find('/') == std::string::npos || !system_path(spec.prlimit))
    return "prlimit (util-linux) is not in /usr/bin";
  const ChildResult child = run_empty_sandbox();
  if (child.outcome == Outcome::exited && child.exit_code == 0) return std::nullopt;
  return fmt::format(
      "bwrap cannot make a sandbox here ({}): it needs unprivileged user "
      "namespaces (sysctl kernel.unprivileged_userns_clone=1, "
      "user.max_user_namespaces > 0)",
      error_tail(child.stderr_tail));
}

}  // namespace psweep
