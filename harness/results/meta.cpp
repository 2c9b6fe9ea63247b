#include "results/meta.hpp"

#include <fmt/format.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <set>

#include "config/program.hpp"
#include "run/runner.hpp"

#ifndef PSWEEP_SOURCE_DIR
#define PSWEEP_SOURCE_DIR "."
#endif
#ifndef PSWEEP_COMPILER
#define PSWEEP_COMPILER "unknown"
#endif
#ifndef PSWEEP_CXX_FLAGS
#define PSWEEP_CXX_FLAGS "unknown"
#endif
#ifndef PSWEEP_BUILD_TYPE
#define PSWEEP_BUILD_TYPE "unknown"
#endif

namespace psweep {
namespace {

std::optional<std::string> git(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"/usr/bin/git", "-C", PSWEEP_SOURCE_DIR};
  argv.insert(argv.end(), args.begin(), args.end());
  auto out = capture_output(argv);
  if (out)
    while (!out->empty() && (out->back() == '\n' || out->back() == ' ')) out->pop_back();
  return out;
}

Json or_null(const std::optional<std::string>& s) { return s ? Json(*s) : Json(nullptr); }

std::optional<std::string> cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0)
      if (auto colon = line.find(':'); colon != std::string::npos) return line.substr(colon + 2);
  return std::nullopt;
}

// Distinct (physical id, core id) pairs: cores without their SMT siblings.
int physical_cores() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, package = "0";
  std::set<std::string> cores;
  while (std::getline(in, line)) {
    auto colon = line.find(':');
    if (colon == std::string::npos || colon + 2 > line.size()) continue;
    if (line.rfind("physical id", 0) == 0) package = line.substr(colon + 2);
    if (line.rfind("core id", 0) == 0) cores.insert(package + "/" + line.substr(colon + 2));
  }
  return static_cast<int>(cores.size());
}

std::optional<std::string> first_line(const char* path) {
  std::ifstream in(path);
  std::string line;
  if (std::getline(in, line)) return line;
  return std::nullopt;
}

std::string hostname() {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  return host;
}

}  // namespace

std::string utc_now() {
  std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string node_name() {
  const char* node = std::getenv("SLURMD_NODENAME");
  return node && *node ? node : hostname();
}

Json slurm_job() {
  auto env = [](const char* name) -> Json {
    const char* value = std::getenv(name);
    return value && *value ? Json(value) : Json(nullptr);
  };
  if (env("SLURM_JOB_ID").is_null()) return nullptr;
  return {{"job_id", env("SLURM_JOB_ID")},
          {"array_job_id", env("SLURM_ARRAY_JOB_ID")},
          {"array_task_id", env("SLURM_ARRAY_TASK_ID")},
          {"cluster", env("SLURM_CLUSTER_NAME")},
          {"node", env("SLURMD_NODENAME")}};
}

Json programs_meta(const Config& config) {
  Json programs = Json::object();
  for (const Program& p : config.programs) {
    const std::string executable = resolve_executable(p.command.front());
    const std::string hash = file_hash(executable);
    Json uses = Json::array();
    for (const char* key : {"T", "P"})
      if (p.facts.uses_param(key)) uses.push_back(key);
    if (p.takes_slow_factor) uses.push_back("slow_factor");
    programs[p.facts.name] = {
        {"command", p.command},
        {"input", p.input_file ? "file" : "stdin"},
        {"uses", uses},
        {"growth", p.facts.growth == 2 ? "N^2" : "N"},
        {"slow_factor", p.takes_slow_factor ? Json(nullptr) : Json(p.slow_factor)},
        {"executable", executable},
        {"executable_hash", hash.empty() ? Json(nullptr) : Json(hash)}};
  }
  return programs;
}

Json build_meta(const MetaInputs& in) {
  Json meta;
  meta["date"] = utc_now();
  meta["config_file"] = in.config->file;
  meta["config"] = in.config->raw;
  meta["command_line"] = in.command_line;
  meta["slurm"] = slurm_job();

  auto commit = git({"rev-parse", "HEAD"});
  auto status = git({"status", "--porcelain", "--untracked-files=no"});
  meta["git"] = {{"commit", or_null(commit)},
                 {"dirty", status ? Json(!status->empty()) : Json(nullptr)},
                 {"source_dir", PSWEEP_SOURCE_DIR}};
  meta["build"] = {{"compiler", PSWEEP_COMPILER},
                   {"flags", PSWEEP_CXX_FLAGS},
                   {"build_type", PSWEEP_BUILD_TYPE},
                   {"note", "psim and psweep come from the same CMake build"}};
  meta["psim"] = {{"path", in.psim}, {"engines", in.declaration->engine_names()}};
  meta["declaration"] = in.declaration->json;
  meta["programs"] = programs_meta(*in.config);
  // What starts a run of P ranks, placeholders unfilled: the config's, or the default.
  meta["launcher"] = in.config->launcher;
  // psim's own OpenMP, from its declaration (null when psim could not be asked).
  meta["openmp"] = in.declaration->json.value("openmp", Json{{"version", nullptr}});

  utsname u{};
  uname(&u);
  meta["machine"] = {{"hostname", hostname()},
                     {"cpu_model", or_null(cpu_model())},
                     {"online_cpus", in.online_cores},
                     {"physical_cores", physical_cores()},
                     {"kernel", fmt::format("{} {} {}", u.sysname, u.release, u.version)},
                     {"arch", u.machine}};
  meta["counters"] = {
      {"software", in.counters.software},
      {"hardware", in.counters.hardware},
      {"user_space_only", in.counters.user_only},
      {"perf_event_paranoid", or_null(first_line("/proc/sys/kernel/perf_event_paranoid"))},
      {"note", in.counters.note}};
  meta["ceilings"] = in.ceilings;
  return meta;
}

}  // namespace psweep
