// Run loop: see run_loop.hpp.
#include "sweep/run_loop.hpp"

#include <fmt/format.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include "config/launcher.hpp"
#include "config/program.hpp"
#include "particle/wait_policy.hpp"
#include "results/csv.hpp"
#include "results/results.hpp"
#include "run/command.hpp"
#include "run/final_state.hpp"
#include "run/neighbour.hpp"
#include "run/record.hpp"
#include "run/run_user.hpp"
#include "sweep/progress.hpp"

namespace fs = std::filesystem;

namespace psweep {

std::vector<std::string> write_inputs(const std::vector<RunSpec>& runs, const fs::path& out) {
  fs::create_directories(out / "inputs");
  std::vector<std::string> inputs(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!runs[i].scene_file.empty()) {
      inputs[i] = runs[i].scene_file;
      continue;
    }
    inputs[i] = (out / "inputs" / (runs[i].id + ".in")).string();
    write_file_atomically(inputs[i], random_scene_input(runs[i].params));
  }
  return inputs;
}

namespace {

// `scene_file` (psim --write-scene's) as its judging scene: print mode, S at most `steps`, the
// same particles.
std::string judging_scene(const std::string& scene_file, std::int64_t steps) {
  std::istringstream in(read_file(scene_file));
  std::string n, l, r, s, mode, rest;
  std::getline(in, n);
  std::getline(in, l);
  std::getline(in, r);
  std::getline(in, s);
  std::getline(in, mode);
  std::ostringstream out;
  out << n << '\n'
      << l << '\n'
      << r << '\n'
      << std::min<std::int64_t>(std::stoll(s), steps) << "\nprint\n"
      << in.rdbuf();
  return out.str();
}

}  // namespace

std::vector<ProgramScene> write_program_scenes(const Config& config,
                                               const std::vector<RunSpec>& runs,
                                               std::vector<std::string>& inputs,
                                               const fs::path& out, const std::string& psim) {
  std::vector<ProgramScene> scenes(runs.size());
  // A scene shared by several configurations (each T of a program) is written once.
  std::map<std::string, std::pair<std::string, ProgramScene>> written;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!config.program(runs[i].params.engine)) continue;
    const std::string scene =
        fmt::format("{}|{}", runs[i].scene_file.empty() ? read_file(inputs[i]) : inputs[i],
                    fmt::join(write_scene_arguments(runs[i], "", "", ""), " "));
    auto [at, fresh] = written.try_emplace(scene);
    if (fresh) {
      const std::string path = (out / "inputs" / (runs[i].id + "-particles.in")).string();
      const ChildResult child = run_child(write_scene_arguments(runs[i], psim, inputs[i], path),
                                          current_environment(), config.timeout_s, nullptr);
      if (child.outcome != Outcome::exited || child.exit_code != 0)
        throw std::runtime_error(fmt::format("psim --write-scene for {}: {}", runs[i].id,
                                             error_tail(child.stderr_tail)));
      const auto particles = read_scene_file(path);
      ProgramScene& p = at->second.second;
      at->second.first = path;
      p.output_limit = output_limit(*particles);
      p.particles = particles->size();
      if (particles->mode != particle::OutputMode::print) {
        const std::int64_t steps = config.judge_steps.value_or(particles->steps);
        p.judge_input = (out / "inputs" / (runs[i].id + "-judge.in")).string();
        write_file_atomically(p.judge_input, judging_scene(path, steps));
        p.judge_limit = output_limit(*read_scene_file(p.judge_input));
        p.whole = steps >= particles->steps;
      }
    }
    inputs[i] = at->second.first;
    scenes[i] = at->second.second;
  }
  return scenes;
}

namespace {

// A run that was not started: what exec would have said, without forking a sandbox for it.
ChildResult not_started(const std::string& path, const std::string& why) {
  ChildResult r;
  r.outcome = Outcome::exited;
  r.exit_code = 127;
  r.stderr_tail = fmt::format("psweep: cannot execute {}: {}", path, why);
  return r;
}

// The first T of psweep's CPUs (P x T for a program of P ranks: each rank's T threads), so that
// a program's threads stay where OMP_PLACES would put psim's; none (psweep's own) when T is
// unknown or more than there are.
std::vector<int> pinned_cpus(const RunSpec& run) {
  cpu_set_t set;
  if (!run.params.T || sched_getaffinity(0, sizeof set, &set) != 0) return {};
  const std::int64_t wanted = run_threads(run.params);
  std::vector<int> cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE && static_cast<std::int64_t>(cpus.size()) < wanted; ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return static_cast<std::int64_t>(cpus.size()) == wanted ? cpus : std::vector<int>{};
}

// Before an external program runs: waits (at most quiet_wait_s) until no more tasks run than when
// the sweep began, so that nothing of an earlier run (or anything else) shares its CPUs unseen;
// says so when the machine stays busier. Returns how many more run (runs.csv's busy_tasks: make
// grade excludes such runs from its points).
int await_quiet(int quiet, double wait_s, const RunSpec& run, Progress& progress) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  int now = particle::other_running_tasks();
  while (now > quiet && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    now = particle::other_running_tasks();
  }
  if (now > quiet)
    progress.note(
        fmt::format("psweep: {} {}: {} other tasks running, {} when the sweep began: "
                    "timed anyway",
                    run.id, run.params.engine, now, quiet));
  return std::max(0, now - quiet);
}

}  // namespace

Launch child_launcher(const Config& config, const std::string& psim,
                      const CounterAvailability* counters, Tier* tier) {
  return [&config, psim, counters, tier, parent_env = current_environment(),
          cpus = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN))](
             const RunSpec& run, const RunFiles& files) {
    std::optional<BusyNeighbour> neighbour;  // lives exactly as long as the run
    if (run.params.neighbour == "busy") neighbour.emplace(BusyNeighbour::last_cpu());
    const Program* program = config.program(run.params.engine);
    if (!program) {
      // A run of P ranks: the launcher's words, then psim's (rank 0 writes the metrics).
      std::vector<std::string> argv = launcher_arguments(config.launcher, run.params, cpus);
      for (std::string& word : psim_arguments(run, psim, files.input, files.metrics))
        argv.push_back(std::move(word));
      return run_child(argv, child_environment(run, parent_env), config.timeout_s, counters);
    }
    const std::vector<std::string> argv = program_arguments(*program, run.params, files.input);
    if (auto why = cannot_execute(argv[0])) return not_started(argv[0], *why);
    ChildIo io;
    io.stdin_path = program->input_file ? "" : files.input;
    io.stdout_path = files.output;
    // RLIMIT_FSIZE bounds every file the run writes, not its output alone: a program of ranks
    // (OpenMPI's) writes shared-memory files of megabytes into /dev/shm and /tmp (killed by
    // SIGXFSZ at a scene's output limit of kilobytes), which the sandbox's folders of disk_mib
    // bound already; its output is then held to its limit after the run (output_bytes).
    io.file_size_limit =
        program->facts.uses_param("P")
            ? std::max<std::uint64_t>(files.output_limit,
                                      static_cast<std::uint64_t>(program->limits.disk_mib) << 20)
            : files.output_limit;
    std::vector<std::string> env =
        child_environment(run, tier ? std::vector<std::string>{} : parent_env);
    for (const auto& [name, value] : program->env) env.push_back(name + "=" + value);
    if (!tier)  // --unconfined: as the grader, with the grader's environment
      return run_child(argv, env, config.timeout_s, counters, io);
    io.cpus = pinned_cpus(run);
    io.confined = true;
    run_as_own_user_if_root(io);
    return tier->run(*program, argv, env, config.timeout_s,
                     static_cast<int>(run_threads(run.params)), io.file_size_limit, io,
                     counters);
  };
}

namespace {

// What a program's output holds on disk: its size, or its blocks where a program reserved more
// than it wrote (fallocate with FALLOC_FL_KEEP_SIZE kept 512 MiB behind a few bytes of output).
// Blocks beyond the limit (with 1 MiB for the file system's rounding) are the limit's breach:
// the file is emptied, which frees them, and the run is too_much_output.
std::uint64_t output_bytes(const std::string& path, std::uint64_t limit) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return 0;
  const auto size = static_cast<std::uint64_t>(st.st_size);
  const auto held = static_cast<std::uint64_t>(st.st_blocks) * 512;
  if (limit == 0 || held <= std::max(size, limit) + (std::uint64_t{1} << 20)) return size;
  truncate(path.c_str(), 0);
  return std::max(held, limit);
}

// How much a verdict says is wrong: a configuration's check is the worse of its two.
int severity(const std::string& verdict) {
  static const std::vector<std::string> order = {"exact", "consistent", "ambiguous",
                                                 "error", "violations", "malformed"};
  const auto at = std::find(order.begin(), order.end(), verdict);
  return static_cast<int>(at - order.begin());
}

// The program's judging run on `scene`'s judging scene (print mode, S capped), its output kept
// as out/outputs/<id>.judge.out and judged step by step; `error` when the run did not end ok.
Judgement judging_run(const LoopSetup& setup, const Launch& launch, const RunSpec& run,
                      const ProgramScene& scene) {
  const fs::path folder = setup.out / "outputs";
  const std::string output = (folder / (run.id + ".judge.out")).string();
  const ChildResult child = launch(run, RunFiles{scene.judge_input, "", output, scene.judge_limit});
  const std::string what =
      fmt::format("judging run (print mode, S = {})",
                  std::min(run.params.S, setup.config->judge_steps.value_or(run.params.S)));
  const Record r = make_program_record(run, 0, child, output_bytes(output, scene.judge_limit),
                                       scene.judge_limit, setup.config->timeout_s, setup.cores);
  Judgement j;
  if (r.status != Status::ok) {
    j.verdict = "error";
    j.detail = fmt::format("{}: {}: {}", what, to_string(r.status), r.error);
  } else {
    j = setup.judge(run, scene.judge_input, output,
                    (folder / (run.id + ".judge.check.json")).string());
    j.detail = fmt::format("{}: {}", what, j.detail);
  }
  j.seconds += child.process_s;
  return j;
}

// A judging run's output larger than this is removed once judged (a whole-length print run of
// N = 1000, S = 1000 takes 65 MB): the scene in out/inputs/ reproduces it.
constexpr std::uintmax_t kKeptJudgeOutput = std::uintmax_t{16} << 20;

// A violation at the scene's last time unit: the final state `mine` is not `reference`.
Judgement final_state_violation(const RunSpec& run, const std::string& difference,
                                const std::string& what) {
  Judgement j;
  j.verdict = "violations";
  j.first_step = std::to_string(run.params.S);
  j.detail = fmt::format("{}: {}", what, difference);
  return j;
}

// The timed run's final state against the whole-length judging run's: a correct program prints
// the same in both modes (the model is deterministic); one that does less when it is timed, or
// prints an answer stored for the scene, does not.
std::optional<Judgement> against_print_mode(const LoopSetup& setup, const RunSpec& run,
                                            const std::string& timed, const ProgramScene& scene) {
  const fs::path judge_output = setup.out / "outputs" / (run.id + ".judge.out");
  const auto reference = final_state(judge_output.string(), scene.particles);
  std::error_code ec;
  if (fs::file_size(judge_output, ec) > kKeptJudgeOutput && !ec) fs::remove(judge_output, ec);
  const auto difference =
      final_state_difference(final_state(timed, scene.particles), reference, "in print mode");
  if (!difference) return std::nullopt;
  return final_state_violation(
      run, *difference,
      fmt::format("timed run (perf mode, T = {}): its final state is not the one it prints in "
                  "print mode for the same scene, as a correct program's is",
                  run.params.T.value_or(1)));
}

// Judges a configuration of a program (docs/programs.md, "The check"): the timed run's output,
// kept as out/outputs/<id>.out with its report beside it (step by step in print mode; in perf
// mode the final state's invariants and the reference's final state), and, for a perf-mode
// scene, one judging run of the program judged step by step (print mode), whose final state the
// timed run's must be when it runs the whole scene, so that a program wrong in the middle of a
// run, or idle when timed, is never `consistent`. The worst verdict fills the record's check
// columns. Returns the time the checks and the judging run took.
double judge_configuration(const LoopSetup& setup, const Launch& launch, const RunSpec& run,
                           const RunFiles& files, const ProgramScene* scene, Record& record) {
  const fs::path folder = setup.out / "outputs";
  fs::create_directories(folder);
  const std::string kept = (folder / (run.id + ".out")).string();
  fs::rename(files.output, kept);
  Judgement j = setup.judge(run, files.input, kept, (folder / (run.id + ".check.json")).string());
  double seconds = j.seconds;
  const auto worst = [&j](Judgement other) {
    if (severity(other.verdict) > severity(j.verdict)) j = std::move(other);
  };
  if (scene && !scene->judge_input.empty()) {
    j.detail = "timed run's final state: " + j.detail;
    const Judgement judged = judging_run(setup, launch, run, *scene);
    seconds += judged.seconds;
    const bool comparable = scene->whole && j.verdict != "malformed" && judged.verdict != "error" &&
                            judged.verdict != "malformed";
    if (severity(judged.verdict) >= severity(j.verdict)) j = judged;
    if (comparable)
      if (auto idle = against_print_mode(setup, run, kept, *scene)) worst(std::move(*idle));
  }
  record.check = j.verdict;
  record.check_first_step = j.first_step;
  record.check_detail = j.detail;
  return seconds;
}

// A later repetition of a judged configuration: its final state must be the judged one's
// (out/outputs/<id>.out), as a deterministic program's is; else the configuration is
// nondeterministic, a violation on this repetition's row.
void compare_repetition(const LoopSetup& setup, const RunSpec& run, int rep,
                        const std::string& output, const ProgramScene& scene, Record& record) {
  const std::string judged = (setup.out / "outputs" / (run.id + ".out")).string();
  if (!fs::exists(judged)) return;
  const auto difference =
      final_state_difference(final_state(output, scene.particles),
                             final_state(judged, scene.particles), "in the judged repetition");
  if (!difference) return;
  const Judgement j = final_state_violation(
      run, *difference,
      fmt::format("nondeterministic: repetition {} (T = {}) prints another final state than the "
                  "judged repetition of the same scene",
                  rep, run.params.T.value_or(1)));
  record.check = j.verdict;
  record.check_first_step = j.first_step;
  record.check_detail = j.detail;
}

// The check of a program's recorded ok repetition: the configuration's first is judged
// (judge_configuration), a later one compared with it (compare_repetition); the verdict, where
// there is one, said on the way. Returns the checks' time.
double check_repetition(const LoopSetup& setup, const Launch& launch, const RunSpec& run, int rep,
                        const RunFiles& files, const ProgramScene* scene,
                        std::set<std::string>& judged, Record& record, Progress& progress) {
  double seconds = 0;
  if (judged.insert(run.id).second)
    seconds = judge_configuration(setup, launch, run, files, scene, record);
  else if (scene)
    compare_repetition(setup, run, rep, files.output, *scene, record);
  if (!record.check.empty())
    progress.note(fmt::format("psweep: {} {}: check: {}: {}", run.id, run.params.engine,
                              record.check, record.check_detail));
  return seconds;
}

// The row of one finished child: psim's metrics (the file read and removed) or a program's
// output size, and the configuration's simulated counts, if it was simulated, in the record's
// empty hardware counters (counters_source says which filled them) and beside them.
Record record_of(const LoopSetup& setup, const RunSpec& run, int rep, const ChildResult& child,
                 const RunFiles& files, bool program) {
  const std::string metrics_text =
      fs::exists(files.metrics) ? read_file(files.metrics) : std::string();
  fs::remove(files.metrics);
  const Config& config = *setup.config;
  Record record = program ? make_program_record(run, rep, child,
                                                output_bytes(files.output, files.output_limit),
                                                files.output_limit, config.timeout_s, setup.cores)
                          : make_record(run, rep, child, metrics_text, config.timeout_s,
                                        setup.cores, *setup.declaration);
  const auto simulated = setup.simulated.find(run.id);
  const bool found = simulated != setup.simulated.end();
  record.counters_source = fill_counters(record.events, found ? &simulated->second : nullptr);
  if (found) record.simulated = simulated->second;
  return record;
}

}  // namespace

LoopTotals run_loop(const LoopSetup& setup, const std::vector<Job>& jobs, const Launch& launch,
                    std::vector<RecordedRun>& recorded) {
  const Config& config = *setup.config;
  const Declaration& declaration = *setup.declaration;
  const std::vector<RunSpec>& runs = *setup.runs;
  const std::string summary_csv = (setup.out / "summary.csv").string();
  fs::create_directories(setup.out / "tmp");
  RowAppender appender((setup.out / "runs.csv").string(), runs_columns(declaration));
  write_summary(summary_csv, runs, recorded);
  std::set<std::string> judged;  // configurations whose program output psim check has judged
  for (const RecordedRun& r : recorded)
    if (r.checked) judged.insert(r.config_id);
  Progress progress(jobs, runs.size(), isatty(STDERR_FILENO) == 1);
  const auto start = std::chrono::steady_clock::now();
  LoopTotals totals;
  const int quiet = particle::other_running_tasks();
  for (std::size_t j = 0; j < jobs.size() && !interrupt_signal(); ++j) {
    const Job& job = jobs[j];
    const RunSpec& run = runs[job.run];
    progress.start(j, describe(run));
    const std::string stem =
        (setup.out / "tmp" / fmt::format("{}-{}{}", run.id, job.warmup ? "w" : "", job.rep))
            .string();
    const Program* program = config.program(run.params.engine);
    const ProgramScene* scene =
        setup.program_scenes.empty() ? nullptr : &setup.program_scenes[job.run];
    const RunFiles files{setup.inputs[job.run], stem + ".json", program ? stem + ".out" : "",
                         scene ? scene->output_limit : 0};
    fs::remove(files.metrics);
    std::optional<int> busy_tasks;
    if (program) busy_tasks = await_quiet(quiet, config.quiet_wait_s, run, progress);
    // Which run was under way, for whoever finds the sweep dead (make grade names it).
    if (program)
      write_file_atomically((setup.out / "tmp" / "running").string(),
                            fmt::format("{}\t{}\t{}\n", run.params.engine, run.id, job.rep));
    const ChildResult child = launch(run, files);
    totals.children_s += child.process_s;
    if (child.outcome == Outcome::interrupted) {  // not a result: --resume runs it again
      fs::remove(files.metrics);
      if (program) fs::remove(files.output);
      break;
    }
    Record record = record_of(setup, run, job.rep, child, files, program != nullptr);
    record.busy_tasks = busy_tasks;
    if (program && !job.warmup && record.status == Status::ok)
      totals.checks_s +=
          check_repetition(setup, launch, run, job.rep, files, scene, judged, record, progress);
    if (program) fs::remove(files.output);
    // Not a result of the configuration but of the disk: recorded, --resume would never run it.
    // psim's word only: a program's stderr is its own, and one that printed this message once
    // stopped a whole grading (its full disk is its folder's, a verdict like any other).
    if (!program && record.status == Status::failed &&
        record.error.find(std::strerror(ENOSPC)) != std::string::npos)
      throw std::runtime_error(fmt::format("rep {} {}: {}", job.rep, run.id, record.error));
    progress.finish(j, child.process_s);
    ++totals.finished;
    if (record.status != Status::ok) {
      ++totals.not_ok;
      progress.note(fmt::format("psweep: {} {} {}: {}: {}", job.warmup ? "warm-up" : "rep", job.rep,
                                run.id, to_string(record.status), record.error));
    }
    if (job.warmup) continue;
    record.node = setup.node;
    appender.append(runs_row(record, declaration));
    recorded.push_back(
        {run.id, job.rep, record.status == Status::ok, record.wall_s(), !record.check.empty(),
         record.metrics ? builds_per_substep(record.metrics->value("broad_phase_builds"),
                                             record.metrics->value("time_reached"),
                                             run.params.slow_factor)
                        : std::nullopt});
    write_summary(summary_csv, runs, recorded);
  }
  progress.done();
  totals.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Scratch for the child being run, nothing else: a psim killed while writing its metrics
  // leaves its own temporary file beside them.
  std::error_code ec;
  fs::remove_all(setup.out / "tmp", ec);
  return totals;
}

}  // namespace psweep
