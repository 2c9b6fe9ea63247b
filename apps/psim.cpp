// psim: one simulation. Reads the 2019 format from INPUT or stdin, writes states to stdout and,
// with --metrics, one JSON object describing the run. Exit 0 ok, 2 bad input or usage, 1 internal,
// 130 or 143 when SIGINT or SIGTERM stopped the run (the state reached and the metrics written).
#include "psim.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "check.hpp"
#include "option_values.hpp"
#include "particle/describe.hpp"
#include "particle/io.hpp"
#include "particle/limits.hpp"
#include "particle/overlaps.hpp"
#include "particle/processes.hpp"
#include "particle/simulation.hpp"
#include "particle/wait_policy.hpp"
#include "usage_error.hpp"
#include "whole_file.hpp"

namespace {

using particle::InputError;

struct Cli {
  particle::RunOptions run;
  particle::RandomInit init;
  std::string speed, input, metrics, write_scene;
  std::pair<std::int64_t, std::string> state_at{-1, ""};  // --state-at H FILE; H < 0: not asked
  bool list_engines = false;
  particle::WaitPolicy wait;
  bool describe = false;
  bool header = false;
  // The options given that shape only a random scene: errors when the input gives the particles,
  // since they would have no effect.
  std::vector<std::string> random_scene_options;
};

particle::SpeedRange parse_speed(const std::string& text) {
  const auto comma = text.find(',');
  double v[2];
  const std::string parts[2] = {text.substr(0, comma),
                                comma == std::string::npos ? "" : text.substr(comma + 1)};
  for (int k = 0; k < 2; ++k) {
    const auto [end, ec] =
        std::from_chars(parts[k].data(), parts[k].data() + parts[k].size(), v[k]);
    if (comma == std::string::npos || ec != std::errc() ||
        end != parts[k].data() + parts[k].size() || !std::isfinite(v[k]))
      throw InputError("--speed: expected MIN,MAX (two finite numbers), got " +
                       particle::quoted(text));
  }
  if (v[0] < 0 || v[1] < v[0])
    throw InputError("--speed: need 0 <= MIN <= MAX, got " + particle::quoted(text));
  return {v[0], v[1]};
}

nlohmann::json value_json(const particle::MetricValue& v) {
  switch (v.type) {
    case particle::MetricValue::Type::real:
      return v.real;
    case particle::MetricValue::Type::count:
      return v.count;
    case particle::MetricValue::Type::flag:
      return v.flag;
  }
  return nullptr;
}

// libgomp's own waits, at a parallel region's start and end (the engines' teams wait at their own
// barrier, engine/src/parallel/team.hpp), spin 300,000 rounds (about 8 ms here) before they sleep.
// On the project's VMs the kernel starts or wakes a thread on the CPU of the thread that started
// or woke it, which then spins there, on the CPU the other needs, until the idle CPU takes that
// one over at a scheduler tick: a team of two took 1.5 to 10 ms to start, 0.1 ms with 1,000
// rounds (26 us; docs/engines.md, "Threads"). A choice of the user's stands. As a constructor of
// priority 101 it runs before libgomp's own, which reads the environment, where psim links the
// runtime in (link_runtimes_statically); a sanitizer's build loads libgomp.so, whose constructor
// has read it before psim's run, so there psim chooses nothing (and reports nothing it chose).
constexpr const char* kLibgompSpinCount = "1000";
bool chose_spin_count = false;  // constant-initialized: read and written before any constructor

#ifdef PARTICLE_LIBGOMP_LINKED_IN
[[gnu::constructor(101)]] void choose_libgomp_spin_count() {
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
  setenv("GOMP_SPINCOUNT", kLibgompSpinCount, 0);
  chose_spin_count = true;
}
#endif

// GOMP_SPINCOUNT as libgomp read it (psim's choice, or the user's); null where unset, the
// runtime's own for its OMP_WAIT_POLICY.
nlohmann::json spin_count() {
  const char* set = chose_spin_count ? kLibgompSpinCount : std::getenv("GOMP_SPINCOUNT");
  return set ? nlohmann::json(set) : nlohmann::json(nullptr);
}

// Once libgomp has read it: a program psim executes (itself again, passive, or psim-mpi) does
// not inherit psim's choice, and makes its own.
void forget_spin_count() {
  if (chose_spin_count) unsetenv("GOMP_SPINCOUNT");
}

// The run's facts, then every declared metric (particle::metrics()) in its section.
nlohmann::json metrics_json(const Cli& cli, const particle::Scene& scene,
                            const particle::RunReport& report) {
  nlohmann::json j = {
      {"engine", report.engine},
      {"engine_requested", cli.run.engine},
      {"threads", report.threads},
      {"cpus", report.cpus},
      {"wall_s", report.wall_s},
      {"state_hash", fmt::format("{:016x}", particle::state_hash(scene.particles))},
      {"wait_policy", cli.wait.policy},
      {"wait_policy_reason", cli.wait.reason},
      {"omp_spin_count", spin_count()},
      {"N", scene.size()},
      {"L", scene.L},
      {"r", scene.r},
      {"S", scene.steps},
      {"slow_factor", cli.run.slow_factor},
      {"wall_stop", particle::wall_stop_name(cli.run.wall_stop)},
      {"overlap", particle::overlap_name(cli.run.overlap)},
      {"seed", cli.init.seed},
  };
  for (const particle::MetricInfo& m : particle::metrics()) {
    const particle::MetricValue value = m.value(report);
    if (!value.present) continue;  // does not apply to this run: psweep's cell stays empty
    const std::string section(particle::section(m.kind));
    nlohmann::json& into = section.empty() ? j : j[section];
    into[std::string(m.key)] = value_json(value);
  }
  return j;
}

// Chooses how OpenMP threads wait (wait_policy.hpp) before the runtime starts any thread. The
// runtime read OMP_WAIT_POLICY when it was loaded, so a passive choice sets the variable and runs
// psim again in place (once: the variable is then set; stdin is not read yet); PSIM_WAIT_REASON
// carries the reason across. A policy the user set is kept.
particle::WaitPolicy settle_wait_policy(int threads, char** argv) {
  if (const char* set = std::getenv("OMP_WAIT_POLICY")) {
    const char* reason = std::getenv("PSIM_WAIT_REASON");
    return {set, reason ? reason : "OMP_WAIT_POLICY"};
  }
  // One thread waits at no barrier: nothing to choose, so neither /proc/stat's samples (up to 2 ms
  // on a busy machine) nor a re-execution (a second start of the process) to pay.
  if (threads == 1) return {"default", "one thread"};
  const particle::WaitPolicy chosen = particle::choose_wait_policy(
      threads, particle::available_cpus(), particle::other_running_tasks());
  if (chosen.policy == "passive") {
    setenv("OMP_WAIT_POLICY", "passive", 1);
    setenv("PSIM_WAIT_REASON", chosen.reason.c_str(), 1);
    particle::unpin_initial_thread();
    execv("/proc/self/exe", argv);
    std::fprintf(stderr, "psim: warning: cannot re-execute for OMP_WAIT_POLICY=passive (%s)\n",
                 std::strerror(errno));
    return {"default", chosen.reason + ", re-execution failed"};
  }
  return chosen;
}

// SIGINT and SIGTERM during the simulation ask it to stop at the next sub-step boundary: the
// handler only stores (async-signal-safe), the engine reads stop_request once per sub-step.
// A second signal ends psim at once (whoever sends it does not want to wait), saying so.
std::atomic<bool> stop_request{false};
volatile std::sig_atomic_t stop_signal = 0;
static_assert(std::atomic<bool>::is_always_lock_free, "stored from a signal handler");

void on_stop_signal(int signal) {
  if (stop_signal != 0) {
    static const char message[] =
        "psim: a second signal: stopped at once; the final state and files not written\n";
    [[maybe_unused]] auto n = write(STDERR_FILENO, message, sizeof message - 1);
    _exit(128 + signal);
  }
  stop_signal = signal;
  stop_request.store(true, std::memory_order_relaxed);
}

void catch_stop_signals() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// Overlapping particles in an input file run (the model handles them) but are usually a mistake.
void warn_overlaps(const particle::Scene& scene, const std::string& source,
                   const particle::RunOptions& run) {
  const particle::Overlaps o = particle::find_overlaps(scene, run.threads);
  if (o.pairs == 0) return;
  const particle::Particles& p = scene.particles;
  const double distance =
      std::hypot(p.x[o.first_j] - p.x[o.first_i], p.y[o.first_j] - p.y[o.first_i]);
  std::fprintf(
      stderr, "%s\n",
      fmt::format("psim: warning: {}: {} {} (centres closer than 2r = {}), the first {} "
                  "and {} at distance {:.8g}; {}",
                  source, o.pairs,
                  o.pairs == 1 ? "pair of particles overlaps" : "pairs of particles overlap",
                  scene.contact_distance(), o.first_i, o.first_j, distance,
                  run.overlap == particle::Overlap::always
                      ? "each collides at once, receding or not (--overlap always)"
                      : "approaching pairs collide at once, receding ones pass through each other")
          .c_str());
}

std::string source(const Cli& cli) {
  return cli.input.empty() || cli.input == "-" ? "<stdin>" : cli.input;
}

// read(stream, source) on the input file, or stdin.
template <class Read>
auto read_input(const Cli& cli, Read read) {
  if (cli.input.empty() || cli.input == "-") return read(std::cin, source(cli));
  std::ifstream in(cli.input);
  if (!in) throw InputError(cli.input + ": cannot open the input file");
  return read(in, cli.input);
}

// --header: the input's header as psim reads it, for scripts that need N, L, r, S or the mode
// (analysis/common/trajectory.py): one reader, one set of rules and messages.
int print_header(const Cli& cli) {
  const particle::SceneHeader h = read_input(cli, particle::read_scene_header);
  const nlohmann::ordered_json json = {
      {"N", h.n},
      {"L", h.L},
      {"r", h.r},
      {"S", h.steps},
      {"mode", h.mode == particle::OutputMode::print ? "print" : "perf"}};
  std::printf("%s\n", json.dump().c_str());
  return 0;
}

// --write-scene FILE: the scene as read or drawn, every particle given, so that another program
// (psweep's external programs, psim check) reads the same particles: each value as the shortest
// text that reads back as the same double, not the output's %.8f, which rounds them.
void write_scene(const particle::Scene& scene, lab::WholeFile& file) {
  std::FILE* out = file.get();
  fmt::print(out, "{}\n{}\n{}\n{}\n{}\n", scene.size(), scene.L, scene.r, scene.steps,
             scene.mode == particle::OutputMode::print ? "print" : "perf");
  const particle::Particles& p = scene.particles;
  for (std::size_t i = 0; i < p.size(); ++i)
    fmt::print(out, "{} {} {} {} {}\n", i, p.x[i], p.y[i], p.vx[i], p.vy[i]);
  file.commit();
}

// An output written over the input scene or over the other output would lose one of them; a
// stream (/dev/null twice) loses nothing.
void check_outputs_apart(const Cli& cli, const std::optional<lab::WholeFile>& metrics,
                         const std::optional<lab::WholeFile>& state_file) {
  const auto input =
      particle::file_id(cli.input.empty() || cli.input == "-" ? "/dev/stdin" : cli.input);
  for (const auto* file : {&metrics, &state_file}) {
    if (!*file || !(*file)->target().atomic()) continue;
    if (input && (*file)->target().id == input)
      throw InputError(fmt::format("{}: {} is the input scene {}; name another file",
                                   (*file)->option(), (*file)->path(), source(cli)));
  }
  if (metrics && state_file && metrics->target().atomic() &&
      metrics->target().same_file(state_file->target()))
    throw InputError(fmt::format("--state-at: {} is also the --metrics file; name another file",
                                 state_file->path()));
}

// The files psim writes besides stdout, opened before any input is read: a path that cannot be
// written is an error first. --write-scene excludes the other two (CLI11), so it takes the
// second slot of the check that no output is the input.
struct Outputs {
  explicit Outputs(const Cli& cli) {
    if (!cli.metrics.empty()) metrics.emplace(cli.metrics, "--metrics");
    if (cli.state_at.first >= 0) state_file.emplace(cli.state_at.second, "--state-at");
    if (!cli.write_scene.empty()) state_file.emplace(cli.write_scene, "--write-scene");
    check_outputs_apart(cli, metrics, state_file);
  }
  std::optional<lab::WholeFile> metrics, state_file;
};

// The scene of the run, read and checked against the options that shape it.
particle::Scene load_scene(const Cli& cli) {
  particle::Scene scene = read_input(cli, [&](std::istream& in, const std::string& where) {
    return particle::read_scene(in, where, cli.init, cli.run.threads);
  });
  if (!scene.generated && !cli.random_scene_options.empty())
    throw InputError(cli.random_scene_options.front() + ": has no effect: " + source(cli) +
                     " gives every particle's position and velocity; leave it out");
  particle::check_representable(scene, cli.run.slow_factor, source(cli), cli.run.engine);
  return scene;
}

// --state-at H FILE: the state at time unit H (step lines), to compare trajectories of engines;
// written into the file's temporary when H is reached, committed only if it was.
class StateAt {
 public:
  StateAt(std::int64_t step, std::optional<lab::WholeFile>& file) : step_(step), file_(file) {}
  bool inside(std::int64_t steps) const { return step_ > 0 && step_ < steps; }
  void write(std::int64_t step, const particle::Particles& p) {
    if (step != step_) return;
    writer_.emplace(file_->get());
    writer_->write(step, p);
  }
  void commit(const std::string& reached, const std::string& path) {
    if (writer_) {
      writer_.reset();  // flushes into the temporary, which commit() closes
      file_->commit();
    } else if (file_) {
      std::fprintf(stderr,
                   "psim: warning: --state-at: the run stopped at time %s, before H = %lld: %s "
                   "not written\n",
                   reached.c_str(), static_cast<long long>(step_), path.c_str());
    }
  }

 private:
  std::int64_t step_;
  std::optional<lab::WholeFile>& file_;
  std::optional<particle::StateWriter> writer_;
};

// After the run: the final state, --state-at and --metrics, and the exit status.
int conclude(const Cli& cli, const particle::Scene& scene, const particle::RunReport& report,
             particle::StateWriter& writer, StateAt& state_at, Outputs& out) {
  if (const std::string warning = particle::energy_warning(report.physics); !warning.empty())
    std::fprintf(stderr, "psim: warning: %s\n", warning.c_str());
  const std::string reached =
      report.interrupted ? particle::time_label(report.time_reached) : std::to_string(scene.steps);
  writer.write_final(reached, scene.particles);
  writer.flush();
  if (!report.interrupted) state_at.write(scene.steps, scene.particles);
  state_at.commit(reached, cli.state_at.second);
  if (out.metrics) {
    std::fputs((metrics_json(cli, scene, report).dump(2) + '\n').c_str(), out.metrics->get());
    out.metrics->commit();
  }
  if (!report.interrupted) return 0;
  std::fprintf(stderr,
               "psim: interrupted by SIG%s at time %s of S = %lld: wrote the state reached%s\n",
               sigabbrev_np(stop_signal), reached.c_str(), static_cast<long long>(scene.steps),
               out.metrics ? " and the metrics" : "");
  return 128 + stop_signal;  // the shell's convention for a signal: 130 SIGINT, 143 SIGTERM
}

// The options of the run itself: the stop request, stage times when the metrics are written.
particle::RunOptions run_options(const Cli& cli) {
  particle::RunOptions run = cli.run;
  run.profile = !cli.metrics.empty();
  run.stop = &stop_request;
  return run;
}

// A follower of the mpi engine's leader (a rank other than 0): its share of the leader's run; the
// leader alone writes. Its status: the run's, or the leader's when it ended before starting the
// followers.
int follow(const Cli& cli) {
  if (const std::optional<int> status = particle::await_leader()) return *status;
  catch_stop_signals();
  const particle::RunReport report = particle::follow(run_options(cli));
  return report.interrupted ? 128 + stop_signal : 0;
}

int run(const Cli& cli) {
  if (const std::string why = particle::engine_unavailable(cli.run.engine); !why.empty())
    throw InputError("--engine " + cli.run.engine + ": " + why);
  // The mpi engine runs one simulation on every process of the launcher's job.
  if (cli.run.engine == "mpi" && !particle::join_processes().leads()) return follow(cli);
  Outputs out(cli);
  particle::Scene scene = load_scene(cli);
  if (!cli.write_scene.empty()) {
    write_scene(scene, *out.state_file);
    return 0;
  }
  if (!scene.generated) warn_overlaps(scene, source(cli), cli.run);
  if (cli.state_at.first > scene.steps)
    throw InputError(fmt::format("--state-at: H must be a time unit in [0, S = {}], got {}",
                                 scene.steps, cli.state_at.first));
  StateAt state_at(cli.state_at.first, out.state_file);

  particle::start_followers();  // nothing can fail on the leader alone from here on
  catch_stop_signals();         // before step 0 is written: who sees it may signal (tests do)
  particle::StateWriter writer(stdout, cli.run.threads);
  writer.write(0, scene.particles);
  writer.flush();
  state_at.write(0, scene.particles);
  // An observer costs a conversion of the state per time unit: only when something is written.
  const bool print = scene.mode == particle::OutputMode::print;
  particle::StepObserver observer;
  if (print || state_at.inside(scene.steps))
    observer = [&](std::int64_t step, const particle::Particles& p) {
      if (print) writer.write(step, p);
      state_at.write(step, p);
    };
  const particle::RunReport report = particle::simulate(scene, run_options(cli), observer);
  return conclude(cli, scene, report, writer, state_at, out);
}

// psim's exit status on an error, where the mpi engine's other processes end with it too.
int failed(int status) {
  particle::fail_processes(status);
  return status;
}

// "auto, brute, ...", in `psim --list-engines` order.
std::string engine_list() {
  std::string list;
  for (const auto& e : particle::engine_names()) list += (list.empty() ? "" : ", ") + e;
  return list;
}

// The option values as given: read by option_values.hpp once CLI11 has split the command line.
struct CliText {
  std::string threads, grid, slow_factor, wall_stop, overlap, seed, metrics, write_scene;
  std::pair<std::string, std::string> state_at;
};

void read_option_values(const CLI::App& app, const CliText& text, Cli& cli) {
  const auto given = [&](const char* option) { return app.count(option) > 0; };
  if (!particle::find_engine_info(cli.run.engine))
    throw InputError(fmt::format("--engine: expected one of {}, got {}", engine_list(),
                                 particle::quoted(cli.run.engine)));
  if (given("--threads"))
    cli.run.threads = static_cast<int>(
        lab::integer_option("--threads", text.threads, 1, particle::max_threads()));
  else if (omp_get_max_threads() > particle::max_threads())
    throw InputError(fmt::format("OMP_NUM_THREADS: expected at most {} threads, got {}",
                                 particle::max_threads(), omp_get_max_threads()));
  if (given("--grid"))
    cli.run.grid =
        static_cast<int>(lab::integer_option("--grid", text.grid, 1, particle::kMaxGrid));
  if (given("--slow-factor")) cli.run.slow_factor = lab::slow_factor_option(text.slow_factor);
  if (given("--wall-stop")) cli.run.wall_stop = lab::wall_stop_option(text.wall_stop);
  if (given("--overlap")) cli.run.overlap = lab::overlap_option(text.overlap);
  if (given("--seed")) cli.init.seed = lab::seed_option(text.seed);
  if (given("--speed")) cli.init.speed = parse_speed(cli.speed);
  if (given("--metrics")) cli.metrics = lab::path_option("--metrics", text.metrics);
  if (given("--write-scene")) cli.write_scene = lab::path_option("--write-scene", text.write_scene);
  if (given("--state-at"))
    cli.state_at = {lab::time_unit_option("--state-at", text.state_at.first),
                    lab::path_option("--state-at", text.state_at.second)};
  for (const char* option : {"--seed", "--speed"})
    if (given(option)) cli.random_scene_options.emplace_back(option);
}

// psim's options: CLI11 splits the command line, read_option_values() reads the values.
void add_options(CLI::App& app, Cli& cli, CliText& text) {
  app.add_option("--engine", cli.run.engine, "engine: " + engine_list())
      ->type_name("NAME")
      ->capture_default_str();
  app.add_option("--threads", text.threads,
                 fmt::format("OpenMP threads, 1 to {} (default: OMP_NUM_THREADS or the cores)",
                             particle::max_threads()))
      ->type_name("T");
  app.add_option("--grid", text.grid,
                 fmt::format("cells per side G of the grid engines, 1 to {}", particle::kMaxGrid))
      ->type_name("G")
      ->default_str(std::to_string(cli.run.grid));
  app.add_option("--slow-factor", text.slow_factor,
                 fmt::format("sub-steps per time unit, a power of two from 1 to {}",
                             particle::kMaxSlowFactor))
      ->type_name("K")
      ->default_str(std::to_string(cli.run.slow_factor));
  app.add_option("--wall-stop", text.wall_stop,
                 "after a collision, a wall line stops the crossing coordinate (per-coordinate) "
                 "or the whole motion (whole-motion, the 2019 authors' reading): docs/model.md")
      ->type_name("READING")
      ->default_str("per-coordinate");
  app.add_option("--overlap", text.overlap,
                 "a pair overlapping at a sub-step's start collides at once if it approaches "
                 "(approaching) or whatever its motion (always, the handout read literally): "
                 "docs/model.md")
      ->type_name("READING")
      ->default_str("approaching");
  app.add_option("--seed", text.seed,
                 "seed of the random scene, 0 to 2^64 - 1 (an error when the input gives the "
                 "particles)")
      ->type_name("X")
      ->default_str(std::to_string(cli.init.seed));
  app.add_option("--speed", cli.speed,
                 "speed range MIN,MAX of the random scene, 0 <= MIN <= MAX, finite (default L/(8r) "
                 "to L/4; an error when the input gives the particles)")
      ->type_name("MIN,MAX");
  app.add_option("--metrics", text.metrics, "write a JSON object describing the run to FILE")
      ->type_name("FILE");
  auto* state_at =
      app.add_option("--state-at", text.state_at,
                     "also write the state at time unit H (0 to S) to FILE (lines `H i x y vx "
                     "vy`)")
          ->type_name("H FILE");
  app.add_option("--write-scene", text.write_scene,
                 "write the scene as read or drawn (every particle, each value read back as the "
                 "same double) to FILE and exit without running it")
      ->type_name("FILE")
      ->excludes(state_at)
      ->excludes("--metrics");
  app.add_flag("--list-engines", cli.list_engines, "print the engine names and exit");
  app.add_flag("--describe", cli.describe,
               "print the engines (exact or not, parameters used) and metrics (key, unit, kind) "
               "as JSON and exit");
  app.add_flag("--header", cli.header,
               "print the input's header as JSON ({\"N\", \"L\", \"r\", \"S\", \"mode\"}), read "
               "with a run's rules (exit 2 naming the line when it is bad), and exit");
  app.add_option("INPUT", cli.input, "input file (default: stdin)")->type_name("FILE");
}

}  // namespace

int psim_main(int argc, char** argv) {
  forget_spin_count();
  // `psim check`: the model checker (check/, docs/check.md), with options of its own.
  if (argc > 1 && std::string_view(argv[1]) == "check")
    return particle::check::check_main(argc - 1, argv + 1);
  CLI::App app{"psim: one 2D elastic particle simulation (CS3210 2019 format)", "psim"};
  Cli cli;
  CliText text;
  add_options(app, cli, text);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "psim: %s\n", lab::usage_message(e, "psim").c_str());
    return 2;
  }
  if (cli.describe) {
    std::printf("%s\n", particle::describe_json().c_str());
    return 0;
  }
  if (cli.list_engines) {
    for (const auto& e : particle::engine_names()) std::printf("%s\n", e.c_str());
    return 0;
  }
  try {
    if (cli.header) return print_header(cli);
    read_option_values(app, text, cli);
    particle::validate(cli.run);
    if (const particle::EngineInfo* e = particle::find_engine_info(cli.run.engine); !e->exact)
      std::fprintf(stderr, "psim: warning: engine %s is unsafe: %s\n", cli.run.engine.c_str(),
                   std::string(e->about).c_str());
    // psim-mpi from here on, before this process chooses its threads' waiting (which may run it
    // again) or reads anything: psim-mpi reads the same command line the same way.
    if (cli.run.engine == "mpi") particle::enter_mpi_program(argv);
    cli.wait = settle_wait_policy(particle::resolve_threads(cli.run.threads), argv);
    const int status = run(cli);
    particle::call_off(status);  // --write-scene: the mpi engine's followers wait for a scene
    return status;
  } catch (const std::invalid_argument& e) {  // options no engine can honour: usage error
    std::fprintf(stderr, "psim: %s\n", e.what());
    return failed(2);
  } catch (const InputError& e) {
    std::fprintf(stderr, "psim: %s\n", e.what());
    return failed(2);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "psim: internal error: %s\n", e.what());
    return failed(1);
  }
}
