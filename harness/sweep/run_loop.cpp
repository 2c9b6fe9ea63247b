// Run loop: see run_loop.hpp.
#include "sweep/run_loop.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>

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

Launch psim_launcher(const std::string& psim, double timeout_s,
                     const CounterAvailability* counters) {
  return [psim, timeout_s, counters, parent_env = current_environment()](
             const RunSpec& run, const std::string& input, const std::string& metrics) {
    std::optional<BusyNeighbour> neighbour;  // lives exactly as long as the run
    if (run.params.neighbour == "busy") neighbour.emplace(BusyNeighbour::last_cpu());
    return run_child(psim_arguments(run, psim, input, metrics), child_environment(run, parent_env),
                     timeout_s, counters);
  };
}

LoopTotals run_loop(const LoopSetup& setup, const std::vector<Job>& jobs, const Launch& launch,
                    std::vector<RecordedRun>& recorded) {
  const Config& config = *setup.config;
  const Declaration& declaration = *setup.declaration;
  const std::vector<RunSpec>& runs = *setup.runs;
  const std::string summary_csv = (setup.out / "summary.csv").string();
  fs::create_directories(setup.out / "tmp");
  RowAppender appender((setup.out / "runs.csv").string(), runs_columns(declaration));
  write_summary(summary_csv, runs, recorded);

  Progress progress(jobs, runs.size(), isatty(STDERR_FILENO) == 1);
  const auto start = std::chrono::steady_clock::now();
  LoopTotals totals;
  for (std::size_t j = 0; j < jobs.size() && !interrupt_signal(); ++j) {
    const Job& job = jobs[j];
    const RunSpec& run = runs[job.run];
    progress.start(j, describe(run));
    const std::string metrics =
        (setup.out / "tmp" / fmt::format("{}-{}{}.json", run.id, job.warmup ? "w" : "", job.rep))
            .string();
    fs::remove(metrics);
    const ChildResult child = launch(run, setup.inputs[job.run], metrics);
    totals.children_s += child.process_s;
    if (child.outcome == Outcome::interrupted) {  // not a result: --resume runs it again
      fs::remove(metrics);
      break;
    }
    std::string metrics_text = fs::exists(metrics) ? read_file(metrics) : std::string();
    fs::remove(metrics);
    Record record =
        make_record(run, job.rep, child, metrics_text, config.timeout_s, setup.cores, declaration);
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
    recorded.push_back({run.id, job.rep, record.status == Status::ok,
                        record.metrics ? record.metrics->wall_s : std::nullopt});
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
