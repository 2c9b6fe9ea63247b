// The launcher: see launcher.hpp.
#include "config/launcher.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "config/program.hpp"

namespace psweep {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ConfigError(path + ": " + what);
}

// The value of placeholder `name` for a run; "" for a name the launcher cannot take.
std::string placeholder(const std::string& name, const Params& p, int cpus) {
  const std::int64_t threads = p.T.value_or(1);
  if (name == "P") return cell(p.P);
  if (name == "T") return fmt::format("{}", threads);
  if (name == "rank_cores") return fmt::format("{}", std::clamp<std::int64_t>(cpus, 1, threads));
  return "";
}

}  // namespace

std::vector<std::string> parse_launcher(const Json& launcher, const std::string& path) {
  if (!launcher.is_array() || launcher.empty())
    fail(path,
         "expected a non-empty list of strings, the launcher and its arguments before psim's, "
         "e.g. [\"srun\", \"-n\", \"{P}\"] (no shell)");
  std::vector<std::string> words;
  bool ranks = false;
  for (std::size_t i = 0; i < launcher.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", path, i);
    if (!launcher[i].is_string()) fail(at, "expected a string, got " + launcher[i].dump());
    const std::string word = launcher[i].get<std::string>();
    if (i == 0 && word.empty()) fail(at, "expected the launcher's path or name, got \"\"");
    substitute(word, at, [&](const std::string& name) {
      if (name != "P" && name != "T" && name != "rank_cores")
        fail(at, fmt::format("unknown placeholder {{{}}} (expected {{P}}, {{T}} or {{rank_cores}}; "
                             "{{{{ and }}}} for literal braces)",
                             name));
      ranks = ranks || name == "P";
      return std::string();
    });
    words.push_back(word);
  }
  if (!ranks)
    fail(path,
         "names no {P}: the launcher must start the run's P ranks (mpirun -np {P}, srun -n {P})");
  return words;
}

std::vector<std::string> default_launcher(bool root) {
  std::vector<std::string> words = {"mpirun"};
  if (root) words.push_back("--allow-run-as-root");
  words.insert(words.end(), {"--oversubscribe", "--map-by", "slot:PE={rank_cores}", "--bind-to",
                             "core:overload-allowed", "--mca", "mpi_yield_when_idle", "1", "-np",
                             "{P}"});
  return words;
}

std::vector<std::string> launcher_arguments(const std::vector<std::string>& launcher,
                                            const Params& params, int cpus) {
  if (!params.P) return {};
  std::vector<std::string> words;
  for (std::size_t i = 0; i < launcher.size(); ++i)
    words.push_back(substitute(launcher[i], fmt::format("launcher[{}]", i),
                               [&](const std::string& name) {
                                 return placeholder(name, params, cpus);
                               }));
  words.front() = resolve_executable(words.front());
  return words;
}

}  // namespace psweep
