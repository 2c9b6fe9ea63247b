// Run loop: see run_loop.hpp.
#include "sweep/run_loop.hpp"

#include <fmt/format.h>
#include <sched.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "config/program.hpp"
#include "results/csv.hpp"
#include "results/results.hpp"
#include "run/command.hpp"
#include "run/neighbour.hpp"
#include "run/record.hpp"
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

std::vector<std::uint64_t> write_program_scenes(const Config& config,
                                                const std::vector<RunSpec>& runs,
                                                std::vector<std::string>& inputs,
                                                const fs::path& out, const std::string& psim) {
  std::vector<std::uint64_t> limits(runs.size(), 0);
  // A scene shared by several configurations (each T of a program) is written once.
  std::map<std::string, std::pair<std::string, std::uint64_t>> written;
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
      at->second = {path, output_limit(*read_scene_file(path))};
    }
    std::tie(inputs[i], limits[i]) = at->second;
  }
  return limits;
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

// The first T of psweep's CPUs, so that a program's threads stay where OMP_PLACES would put
// psim's; none (psweep's own) when T is unknown or more than there are.
std::vector<int> pinned_cpus(const RunSpec& run) {
  cpu_set_t set;
  if (!run.params.T || sched_getaffinity(0, sizeof set, &set) != 0) return {};
  std::vector<int> cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE && static_cast<std::int64_t>(cpus.size()) < *run.params.T;
       ++cpu)
    if (CPU_ISSET(cpu, &set)) cpus.push_back(cpu);
  return static_cast<std::int64_t>(cpus.size()) == *run.params.T ? cpus : std::vector<int>{};
}

// bwrap exits 128 + n when the program died of signal n, as a shell does: read it back as the
// signal (a program that exits 139 itself reads as a crash too, as it would under a shell).
ChildResult as_signal(ChildResult r) {
  if (r.outcome == Outcome::exited && r.exit_code > 128 && r.exit_code < 128 + 65) {
    r.outcome = Outcome::signaled;
    r.signal = r.exit_code - 128;
  }
  return r;
}

}  // namespace

Launch child_launcher(const Config& config, const std::string& psim,
                      const CounterAvailability* counters, Stage* stage,
                      std::vector<std::string> hide) {
  return [&config, psim, counters, stage, hide = std::move(hide),
          parent_env = current_environment()](const RunSpec& run, const RunFiles& files) {
    std::optional<BusyNeighbour> neighbour;  // lives exactly as long as the run
    if (run.params.neighbour == "busy") neighbour.emplace(BusyNeighbour::last_cpu());
    const Program* program = config.program(run.params.engine);
    if (!program)
      return run_child(psim_arguments(run, psim, files.input, files.metrics),
                       child_environment(run, parent_env), config.timeout_s, counters);
    const std::vector<std::string> argv = program_arguments(*program, run.params, files.input);
    if (auto why = cannot_execute(argv[0])) return not_started(argv[0], *why);
    ChildIo io;
    io.stdin_path = program->input_file ? "" : files.input;
    io.stdout_path = files.output;
    io.file_size_limit = files.output_limit;
    std::vector<std::string> env = child_environment(run, stage ? std::vector<std::string>{}
                                                                : parent_env);
    for (const auto& [name, value] : program->env) env.push_back(name + "=" + value);
    if (!stage)  // --unconfined: as the grader, with the grader's environment
      return run_child(argv, env, config.timeout_s, counters, io);
    io.cpus = pinned_cpus(run);
    run_as_nobody_if_root(io);
    const Confined c = confine(*program, argv, env, config.timeout_s,
                               static_cast<int>(run.params.T.value_or(1)), files.output_limit,
                               hide, *stage);
    return as_signal(run_child(c.argv, c.env, config.timeout_s, counters, io));
  };
}

namespace {

std::uint64_t output_bytes(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  return ec ? 0 : size;
}

// Keeps the output judged as out/outputs/<id>.out, its report beside it, and fills the record's
// check columns. Returns the check's time.
double judge_output(const LoopSetup& setup, const RunSpec& run, const RunFiles& files,
                    Record& record) {
  const fs::path folder = setup.out / "outputs";
  fs::create_directories(folder);
  const std::string kept = (folder / (run.id + ".out")).string();
  fs::rename(files.output, kept);
  const Judgement j =
      setup.judge(run, files.input, kept, (folder / (run.id + ".check.json")).string());
  record.check = j.verdict;
  record.check_first_step = j.first_step;
  record.check_detail = j.detail;
  return j.seconds;
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
  for (std::size_t j = 0; j < jobs.size() && !interrupt_signal(); ++j) {
    const Job& job = jobs[j];
    const RunSpec& run = runs[job.run];
    progress.start(j, describe(run));
    const std::string stem =
        (setup.out / "tmp" / fmt::format("{}-{}{}", run.id, job.warmup ? "w" : "", job.rep))
            .string();
    const Program* program = config.program(run.params.engine);
    const RunFiles files{setup.inputs[job.run], stem + ".json", program ? stem + ".out" : "",
                         setup.output_limits.empty() ? 0 : setup.output_limits[job.run]};
    fs::remove(files.metrics);
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
    std::string metrics_text = fs::exists(files.metrics) ? read_file(files.metrics) : "";
    fs::remove(files.metrics);
    Record record = program ? make_program_record(run, job.rep, child, output_bytes(files.output),
                                                  files.output_limit, config.timeout_s, setup.cores)
                            : make_record(run, job.rep, child, metrics_text, config.timeout_s,
                                          setup.cores, declaration);
    if (program && !job.warmup && record.status == Status::ok && !judged.count(run.id)) {
      totals.checks_s += judge_output(setup, run, files, record);
      judged.insert(run.id);
      progress.note(fmt::format("psweep: {} {}: check: {}: {}", run.id, run.params.engine,
                                record.check, record.check_detail));
    }
    if (program) fs::remove(files.output);
    // Not a result of the configuration but of the disk: recorded, --resume would never run it.
    if (record.status == Status::failed &&
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
    appender.append(runs_row(record, declaration));
    recorded.push_back(
        {run.id, job.rep, record.status == Status::ok, record.wall_s(), !record.check.empty()});
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
