#include "run/command.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "particle/wait_policy.hpp"
#include "run/runner.hpp"

extern char** environ;

namespace psweep {

std::string random_scene_input(const Params& p) {
  return fmt::format("{}\n{}\n{}\n{}\nperf\n", p.N, p.L, p.r, p.S);
}

namespace {

// The options that draw a random scene (none for a scene file).
void add_scene_options(std::vector<std::string>& argv, const RunSpec& run) {
  const auto& p = run.params;
  if (!run.scene_file.empty()) return;
  if (p.seed) argv.insert(argv.end(), {"--seed", fmt::format("{}", *p.seed)});
  if (p.speed_min)
    argv.insert(argv.end(), {"--speed", fmt::format("{},{}", *p.speed_min, *p.speed_max)});
}

}  // namespace

std::vector<std::string> psim_arguments(const RunSpec& run, const std::string& psim,
                                        const std::string& input, const std::string& metrics_file) {
  const auto& p = run.params;
  std::vector<std::string> argv = {psim, "--engine", p.engine};
  if (p.T) argv.insert(argv.end(), {"--threads", fmt::format("{}", *p.T)});
  if (p.G) argv.insert(argv.end(), {"--grid", fmt::format("{}", *p.G)});
  if (p.slow_factor) argv.insert(argv.end(), {"--slow-factor", fmt::format("{}", *p.slow_factor)});
  if (p.wall_stop != kDefaultWallStop) argv.insert(argv.end(), {"--wall-stop", p.wall_stop});
  if (p.overlap != kDefaultOverlap) argv.insert(argv.end(), {"--overlap", p.overlap});
  add_scene_options(argv, run);
  argv.insert(argv.end(), {"--metrics", metrics_file, input});
  return argv;
}

std::vector<std::string> write_scene_arguments(const RunSpec& run, const std::string& psim,
                                               const std::string& input,
                                               const std::string& scene_file) {
  std::vector<std::string> argv = {psim, "--write-scene", scene_file};
  add_scene_options(argv, run);
  argv.push_back(input);
  return argv;
}

std::vector<std::string> check_arguments(const RunSpec& run, const std::string& psim,
                                         const std::string& scene, const std::string& output,
                                         const std::string& report,
                                         const RequiredReadings& reading,
                                         bool sub_steps_numbered) {
  std::vector<std::string> argv = {psim,     "check",         scene,
                                   output,   "--slow-factor", cell(run.params.slow_factor),
                                   "--json", report};
  if (reading.wall_stop) argv.insert(argv.end(), {"--wall-stop", *reading.wall_stop});
  if (reading.overlap) argv.insert(argv.end(), {"--overlap", *reading.overlap});
  if (sub_steps_numbered && run.params.slow_factor.value_or(1) > 1)
    argv.push_back("--sub-steps-numbered");
  return argv;
}

std::vector<std::string> child_environment(const RunSpec& run,
                                           const std::vector<std::string>& parent) {
  std::vector<std::string> env;
  for (const auto& var : parent)
    if (var.rfind("OMP_", 0) != 0) env.push_back(var);
  if (run.params.T) {
    env.push_back(fmt::format("OMP_NUM_THREADS={}", *run.params.T));
    // Each rank's psim chooses its wait policy from its own threads (docs/engines.md, "Threads"):
    // where the ranks' threads together exceed the CPUs, spinning ones would take the cores the
    // other ranks need, so they wait passively.
    if (run.params.P && run_threads(run.params) > particle::available_cpus())
      env.push_back("OMP_WAIT_POLICY=passive");
    switch (run.pin) {
      case Pin::close:
        env.insert(env.end(), {"OMP_PROC_BIND=close", "OMP_PLACES=cores"});
        break;
      case Pin::spread:
        env.insert(env.end(), {"OMP_PROC_BIND=spread", "OMP_PLACES=cores"});
        break;
      case Pin::none:
        env.push_back("OMP_PROC_BIND=false");
        break;
    }
  }
  return env;
}

std::vector<std::string> current_environment() {
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e) env.emplace_back(*e);
  return env;
}

Declaration ask_psim(const std::string& psim) {
  auto out = capture_output({psim, "--describe"});
  if (!out) throw std::runtime_error(fmt::format("{} --describe failed; is it psim?", psim));
  try {
    return parse_declaration(*out);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("{} --describe: {}", psim, e.what()));
  }
}

}  // namespace psweep
