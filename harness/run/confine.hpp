// Confinement: how an external program runs (docs/programs.md, "Confinement"). A submission is
// someone else's code; it must not forge its verdict, harm the grader or outlive its run.
//
// Each run goes through bubblewrap (bwrap, a kept tool: unprivileged user, PID, network, IPC and
// mount namespaces), started as `nobody` when psweep runs as root:
//   - its own PID namespace: it cannot see or signal psweep or psim, and when it ends the kernel
//     kills everything it started (setsid daemons and double forks included);
//   - no network: a namespace of its own with only a loopback of its own;
//   - a file system of the system's programs and libraries (/usr, /etc), read-only, a fresh
//     tmpfs as its working folder and HOME (/box) and another as /tmp, and its own files
//     read-only under /program; the repository, the results, psim and the other submissions are
//     not there at all;
//   - an environment of PATH, HOME, OMP_* and the config's `env`, nothing of the grader's;
//   - limits set by prlimit inside: CPU seconds, writable memory, processes, open files, the
//     bytes of any file it writes; the tmpfs sizes bound what it keeps.
// Its files are copied first into a stage folder that the run's user can read (Stage), so that a
// grader's home of mode 700 does not hide them from `nobody`, and a submission replaced during the
// sweep is not the one graded.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "run/runner.hpp"
#include "run/tier.hpp"

namespace psweep {

// Files copied for the runs' user to read, in a folder of /tmp removed with the object.
class Stage {
 public:
  Stage();
  ~Stage();
  Stage(const Stage&) = delete;
  Stage& operator=(const Stage&) = delete;

  // The copy of `path` (once per path), readable by everyone and writable by no one. Throws
  // std::runtime_error when it cannot be copied.
  std::string add(const std::string& path);
  // A new empty folder inside the stage, owned by `uid`/`gid` where they are not -1: a contained
  // run's working folder (run/contain.hpp). The caller removes it.
  std::string fresh_folder(int uid, int gid);

 private:
  std::string folder_;
  std::map<std::string, std::string> copies_;
};

// The words of `argv` that name files outside the system's folders (the program, a script it
// runs, its {scene}) replaced by their staged copies; returns the copies, each once.
std::vector<std::string> stage_words(std::vector<std::string>& argv, Stage& stage);

// A run's CPU seconds: the program's limit, else the timeout times its CPUs.
double cpu_seconds(const Limits& limits, double timeout_s, int cpus);

// RLIMIT_AS, which counts what RLIMIT_DATA does not (a 3 GiB shared mapping and a raised stack
// both passed memory_mib = 2048, issue 40): the memory limit, plus what a program maps without
// writing it, its libraries and, per thread, a stack and glibc's malloc arena (64 MiB each).
std::int64_t address_space_mib(std::int64_t memory_mib, int threads);

// The files a writable folder may hold: one per 4 KiB of its size (65536 for disk_mib = 256): a
// million empty files once held 864 MB of kernel memory (issue 40).
std::int64_t folder_files(const Limits& limits);

// The stack's soft and hard limit: the usual default, which a program may no longer raise.
inline constexpr long long kStackBytes = 8 << 20;

// A run as bwrap starts it: its argv (bwrap's) and environment (the program's).
struct Confined {
  std::vector<std::string> argv;
  std::vector<std::string> env;
};

// What the sandbox is made of, beside the program's own argv.
struct SandboxSpec {
  std::string bwrap;    // its path
  std::string prlimit;  // its path (inside: from /usr, read-only)
  // Host file -> path inside (/program/NAME): the staged program and the files its command names.
  std::vector<std::pair<std::string, std::string>> files;
  Limits limits;
  double cpu_s = 0;               // resolved: never 0
  std::uint64_t file_bytes = 0;   // RLIMIT_FSIZE: the output's cap; 0: none
  int threads = 1;                // T: the address space holds a stack and an arena per thread
  std::vector<std::string> hide;  // host folders that the system's folders would show otherwise
  std::vector<std::string> env;   // OMP_* and the config's `env`
};

// bwrap's argv for `program_argv` (its words already mapped to paths inside) under `spec`, and
// the environment inside. Pure: unit-tested without running anything.
Confined sandbox_command(const SandboxSpec& spec, const std::vector<std::string>& program_argv);

// An external program's run under confinement: every command word that names a file outside
// the system's folders (the program, a script it runs, its {scene}) staged and mapped to
// /program/NAME; bwrap and prlimit found on PATH. `env`: its OMP_* and the config's `env`;
// `hide`: the repository and results folders.
Confined confine(const Program& program, const std::vector<std::string>& argv,
                 const std::vector<std::string>& env, double timeout_s, int cpus,
                 std::uint64_t file_bytes, const std::vector<std::string>& hide, Stage& stage);

// Why a program cannot be run as written, before it is run: "not found", "a directory",
// "Permission denied (not executable: chmod +x)", "its interpreter X (the #! line) does not
// exist"; nullopt when it can be executed.
std::optional<std::string> cannot_execute(const std::string& path);

// The least time, of 5, that starting and ending an empty sandbox takes here: part of every
// confined run's process_s, said in meta.json so that a reader can weigh short runs.
double sandbox_start_s();

// Why confinement cannot work on this machine (bwrap or prlimit missing, user namespaces off),
// in one line; nullopt when a confined `true` runs. Runs bwrap once.
std::optional<std::string> confinement_problem();

// The bwrap tier (run/tier.hpp); nullptr and `why` where bwrap cannot make a sandbox here.
std::unique_ptr<Tier> bwrap_tier(const std::vector<std::string>& hide, std::string& why);

}  // namespace psweep
