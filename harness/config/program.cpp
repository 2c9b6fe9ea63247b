// Programs: see program.hpp.
#include "config/program.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include "config/declaration.hpp"
#include "particle/hash.hpp"

namespace psweep {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ConfigError(path + ": " + what);
}

constexpr const char* kPlaceholders = "{T}, {P}, {N}, {K} or {scene}";

bool plain_name(const std::string& name) {
  return !name.empty() && name[0] != '.' && std::all_of(name.begin(), name.end(), [](char ch) {
    return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-' || ch == '.';
  });
}

void read_uses(Program& program, const Json& uses, const std::string& path) {
  if (!uses.is_array())
    fail(path, "expected a list of the parameters it reads: \"T\", \"P\", \"slow_factor\"");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < uses.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", path, i);
    const std::string key = uses[i].is_string() ? uses[i].get<std::string>() : "";
    if (key != "T" && key != "P" && key != "slow_factor")
      fail(at, fmt::format("expected \"T\", \"P\" or \"slow_factor\", got {}", uses[i].dump()));
    if (!seen.insert(key).second) fail(at, fmt::format("\"{}\" given twice", key));
    if (key == "T" || key == "P") program.facts.uses.push_back(key);
    if (key == "slow_factor") program.takes_slow_factor = true;
  }
}

// The command's words, and that each placeholder is one the program can be given.
void read_command(Program& program, const Json& command, const std::string& path) {
  if (!command.is_array() || command.empty())
    fail(path, "expected a non-empty list of strings, the program and its arguments (no shell)");
  bool scene = false, ranks = false;
  for (std::size_t i = 0; i < command.size(); ++i) {
    const std::string at = fmt::format("{}[{}]", path, i);
    if (!command[i].is_string()) fail(at, "expected a string, got " + command[i].dump());
    const std::string word = command[i].get<std::string>();
    if (i == 0 && word.empty()) fail(at, "expected the program's path, got \"\"");
    substitute(word, at, [&](const std::string& name) {
      if (name == "T" && !program.facts.uses_param("T"))
        fail(at, "{T}: add \"T\" to the program's \"uses\" (else its runs have no thread count)");
      if (name == "P" && !program.facts.uses_param("P"))
        fail(at, "{P}: add \"P\" to the program's \"uses\" (else its runs have no rank count)");
      if (name == "scene" && !program.input_file)
        fail(at,
             "{scene}: only with \"input\": \"file\" (with \"stdin\" the scene comes on stdin)");
      if (name != "T" && name != "P" && name != "N" && name != "K" && name != "scene")
        fail(at, fmt::format("unknown placeholder {{{}}} (expected {}; {{{{ and }}}} for literal "
                             "braces)",
                             name, kPlaceholders));
      scene = scene || name == "scene";
      ranks = ranks || name == "P";
      return std::string();
    });
    program.command.push_back(word);
  }
  // A program of P ranks starts them itself (its mpirun inside its command, inside its
  // confinement): without {P} every run would start the same ranks whatever P says.
  if (program.facts.uses_param("P") && !ranks)
    fail(path,
         "names no {P}, but \"P\" is in \"uses\": the command starts the run's P ranks itself "
         "([\"mpirun\", \"-np\", \"{P}\", ...])");
  if (program.input_file && !scene)
    fail(path,
         "\"input\": \"file\" needs {scene} in the command, where the scene file's path goes");
}

// "env": {"NAME": "value"}: what the program is given besides PATH, HOME and OMP_*.
void read_env(Program& program, const Json& env, const std::string& path) {
  if (!env.is_object()) fail(path, "expected an object of NAME: \"value\"");
  for (const auto& [name, value] : env.items()) {
    const std::string at = path + "." + name;
    const bool ok = !name.empty() && !std::isdigit(static_cast<unsigned char>(name[0])) &&
                    std::all_of(name.begin(), name.end(), [](char ch) {
                      return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_';
                    });
    if (!ok) fail(at, "expected a variable name of letters, digits and '_'");
    if (name == "PATH" || name == "HOME" || name.rfind("OMP_", 0) == 0)
      fail(at, "set by psweep (PATH, HOME and OMP_* are the run's own)");
    if (!value.is_string()) fail(at, "expected a string, got " + value.dump());
    program.env.emplace_back(name, value.get<std::string>());
  }
}

Program read_program(const std::string& name, const Json& spec, const std::string& path,
                     const Limits& limits) {
  if (!plain_name(name))
    fail(path, "expected a program name of letters, digits, '_', '-' and '.' (a runs.csv engine)");
  if (!spec.is_object()) fail(path, "expected an object with \"command\": [\"./my_sim\", ...]");
  static const std::vector<std::string> keys = {"command", "input",  "uses",   "slow_factor",
                                                "growth",  "limits", "env",    "numbers"};
  for (const auto& [key, value] : spec.items())
    if (std::find(keys.begin(), keys.end(), key) == keys.end())
      fail(path + "." + key,
           fmt::format("unknown key (expected one of {})", fmt::join(keys, ", ")));
  Program program;
  program.facts.name = name;
  program.facts.program = true;
  program.facts.growth = 2;
  program.limits =
      spec.contains("limits") ? parse_limits(spec["limits"], path + ".limits", limits) : limits;
  if (spec.contains("env")) read_env(program, spec["env"], path + ".env");
  if (spec.contains("input")) {
    const Json& input = spec["input"];
    if (input != "stdin" && input != "file")
      fail(path + ".input", "expected \"stdin\" or \"file\", got " + input.dump());
    program.input_file = input == "file";
  }
  if (spec.contains("uses")) read_uses(program, spec["uses"], path + ".uses");
  program.facts.uses.push_back("slow_factor");  // K reaches the check whatever the program reads
  if (spec.contains("growth")) {
    const Json& growth = spec["growth"];
    if (!growth.is_string())
      fail(path + ".growth", "expected \"N\" or \"N^2\", got " + growth.dump());
    try {
      program.facts.growth = parse_growth(growth.get<std::string>(), path);
    } catch (const std::runtime_error& e) {
      throw ConfigError(e.what());
    }
  }
  if (spec.contains("slow_factor")) {
    if (program.takes_slow_factor)
      fail(path + ".slow_factor",
           "not with \"slow_factor\" in uses: a program takes K at run time ({K}) or was built "
           "for one K (this key), not both");
    Params scratch;
    set_param(scratch, "slow_factor", spec["slow_factor"], path + ".slow_factor");
    program.slow_factor = *scratch.slow_factor;
  }
  if (spec.contains("numbers")) {
    const Json& numbers = spec["numbers"];
    if (numbers != "time units" && numbers != "sub-steps")
      fail(path + ".numbers",
           "expected \"time units\" (the 2019 format) or \"sub-steps\" (every sub-step printed, "
           "numbered to S x K, velocities per sub-step), got " + numbers.dump());
    program.sub_steps_numbered = numbers == "sub-steps";
  }
  if (!spec.contains("command")) fail(path + ".command", "missing (the program and its arguments)");
  read_command(program, spec["command"], path + ".command");
  return program;
}

}  // namespace

std::vector<Program> parse_programs(const Json& programs, const Limits& limits) {
  if (!programs.is_object())
    fail("programs", "expected an object of name: {\"command\": [...], ...}");
  std::vector<Program> out;
  for (const auto& [name, spec] : programs.items())
    out.push_back(read_program(name, spec, "programs." + name, limits));
  return out;
}

Limits parse_limits(const Json& limits, const std::string& path, const Limits& defaults) {
  if (!limits.is_object())
    fail(path, "expected an object of cpu_s, memory_mib, processes, open_files, disk_mib");
  Limits out = defaults;
  for (const auto& [key, value] : limits.items()) {
    const std::string at = path + "." + key;
    if (key == "cpu_s")
      out.cpu_s = positive_number(value, at);
    else if (key == "memory_mib")
      out.memory_mib = positive_integer(value, at);
    else if (key == "processes")
      out.processes = positive_integer(value, at);
    else if (key == "open_files")
      out.open_files = positive_integer(value, at);
    else if (key == "disk_mib")
      out.disk_mib = positive_integer(value, at);
    else
      fail(at, "unknown key (expected one of cpu_s, memory_mib, processes, open_files, disk_mib)");
  }
  // Below these a program cannot start: the loader's files, a thread per CPU, its own stack.
  if (out.processes < 4) fail(path + ".processes", "expected at least 4");
  if (out.open_files < 16) fail(path + ".open_files", "expected at least 16");
  if (out.memory_mib < 16) fail(path + ".memory_mib", "expected at least 16");
  return out;
}

std::string substitute(std::string_view text, const std::string& path,
                       const std::function<std::string(const std::string&)>& value) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char ch = text[i];
    if ((ch == '{' || ch == '}') && i + 1 < text.size() && text[i + 1] == ch) {
      out += ch;
      ++i;
    } else if (ch == '{') {
      const std::size_t close = text.find('}', i);
      if (close == std::string_view::npos)
        fail(path, "unmatched \"{\" (write {{ for a literal brace)");
      out += value(std::string(text.substr(i + 1, close - i - 1)));
      i = close;
    } else if (ch == '}') {
      fail(path, "unmatched \"}\" (write }} for a literal brace)");
    } else {
      out += ch;
    }
  }
  return out;
}

std::vector<std::string> program_arguments(const Program& program, const Params& params,
                                           const std::string& scene) {
  const auto value = [&](const std::string& name) {
    if (name == "T") return cell(params.T);
    if (name == "P") return cell(params.P);
    if (name == "N") return fmt::format("{}", params.N);
    if (name == "K") return cell(params.slow_factor);
    return scene;  // parse_programs let no other name through
  };
  std::vector<std::string> argv;
  for (const std::string& word : program.command)
    argv.push_back(substitute(word, "programs." + program.facts.name, value));
  argv[0] = resolve_executable(argv[0]);
  return argv;
}

std::string resolve_executable(const std::string& command) {
  if (command.find('/') != std::string::npos) return command;
  const char* path = std::getenv("PATH");
  std::string_view dirs = path && *path ? path : "/usr/local/bin:/usr/bin:/bin";
  while (!dirs.empty()) {
    const std::size_t colon = dirs.find(':');
    const std::string dir(dirs.substr(0, colon));
    dirs = colon == std::string_view::npos ? "" : dirs.substr(colon + 1);
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + command;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && access(candidate.c_str(), X_OK) == 0)
      return candidate;
  }
  return command;
}

std::uint64_t output_limit(const particle::Scene& scene) {
  const particle::Particles& p = scene.particles;
  double speeds = 0;  // sum of v^2: no particle of equal mass gets more than all the energy
  for (std::size_t i = 0; i < p.size(); ++i) speeds += p.vx[i] * p.vx[i] + p.vy[i] * p.vy[i];
  const auto width = [](double v) { return fmt::formatted_size("{:.8f}", v) + 1; };  // a sign
  const double line = 4 * 20 + 2 * width(scene.L) + 2 * width(std::sqrt(speeds) * (1 + 1e-9)) + 9;
  const double states = scene.mode == particle::OutputMode::print ? scene.steps + 1.0 : 2.0;
  const double bytes = 2 * line * states * static_cast<double>(p.size());
  return bytes >= 0x1p63 ? std::uint64_t{1} << 63 : static_cast<std::uint64_t>(bytes);
}

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::uint64_t h = particle::kFnv1aBasis;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0)
    h = particle::fnv1a(buffer, static_cast<std::size_t>(in.gcount()), h);
  return fmt::format("fnv1a64:{:016x}", h);
}

}  // namespace psweep
