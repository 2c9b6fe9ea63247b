#include "sweep.hpp"

#include <fmt/format.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "command.hpp"
#include "config.hpp"
#include "csv.hpp"
#include "declaration.hpp"
#include "expansion.hpp"
#include "meta.hpp"
#include "neighbour.hpp"
#include "progress.hpp"
#include "record.hpp"
#include "results.hpp"
#include "runner.hpp"
#include "schedule.hpp"
#include "shard.hpp"
#include "size.hpp"
#include "stats.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string default_psim() {
  if (const char* env = std::getenv("PSIM"); env && *env) return env;
  std::error_code ec;
  auto self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("psim") : (self.parent_path() / "psim").string();
}

// "shard I/N" or "the whole sweep", from a meta.json.
std::string shard_text(const Json& meta) {
  if (!meta.contains("shard")) return "the whole sweep";
  return fmt::format("shard {}/{}", meta["shard"].value("index", 0),
                     meta["shard"].value("count", 0));
}

// Moves the files of an earlier sweep in `out` to out/previous/, replacing what was there.
void set_aside_previous(const fs::path& out) {
  const fs::path previous = out / "previous";
  bool moved = false;
  for (const char* name : {"runs.csv", "summary.csv", "meta.json"}) {
    if (!fs::exists(out / name)) continue;
    if (!moved) {
      fs::remove_all(previous);
      fs::create_directories(previous);
      moved = true;
    }
    fs::rename(out / name, previous / name);
  }
  if (moved)
    std::fprintf(
        stderr,
        "psweep: moved the earlier results in %s to %s (use --resume to continue a sweep)\n",
        out.c_str(), previous.c_str());
}

int sweep(const SweepOptions& opt) {
  Config config = load_config(opt.config_path);
  const std::optional<ShardSpec> shard =
      opt.shard ? std::optional(parse_shard(*opt.shard)) : std::nullopt;
  const std::string psim = opt.psim.value_or(default_psim());
  const bool psim_ok = access(psim.c_str(), X_OK) == 0;
  Declaration declaration;
  if (psim_ok) {
    try {
      declaration = ask_psim(psim);
    } catch (const std::runtime_error& e) {
      throw UsageError(e.what());
    }
  }
  const std::vector<std::string> engines = declaration.engine_names();
  if (psim_ok) check_engines(config, engines);
  const int cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));

  // The shard's configurations by position in the expansion; every one without --shard.
  std::vector<int> shard_of;
  if (shard) shard_of = assign_shards(config, declaration, shard->count);
  const auto in_shard = [&](std::size_t i) { return !shard || shard_of[i] == shard->index - 1; };
  const SweepSize size = measure(config, declaration, in_shard);
  const std::string what = shard ? "shard " + to_string(*shard) : std::string("the sweep");

  if (opt.dry_run) {
    if (opt.count) {
      if (shard) std::printf("%s of %s\n", what.c_str(), config.file.c_str());
      std::fputs(size_report(config, size).c_str(), stdout);
    } else {  // streamed: a listing of 10^7 lines holds one configuration at a time
      std::size_t index = 0;
      for_each_configuration(config, declaration, [&](const Params& p) {
        if (in_shard(index++)) std::printf("%s\n", describe(make_run(config, p)).c_str());
      });
      const std::size_t n = size.total.configurations;
      std::printf(
          "%zu configurations x %d repetitions = %zu runs (+ %zu warm-up runs), pin %s, timeout "
          "%g s\n",
          n, config.repetitions, n * static_cast<std::size_t>(config.repetitions),
          n * static_cast<std::size_t>(config.warmup), to_string(config.pin), config.timeout_s);
    }
    if (!psim_ok) {
      std::fprintf(stderr,
                   "psweep: warning: %s not found; engine names not checked and no axis left out "
                   "(psim --describe says which parameters each engine uses)\n",
                   psim.c_str());
    }
    return 0;
  }
  check_size(config, size.total.configurations, size.total.seconds, opt.yes, what);
  std::vector<RunSpec> runs = expand(config, declaration, in_shard);
  if (!psim_ok)
    throw UsageError(
        fmt::format("psim not found or not executable: {} (use --psim PATH or PSIM=)", psim));

  const fs::path out = opt.out_dir.value_or("results/" + config.name +
                                            (shard ? fmt::format("/shard-{}", shard->index) : ""));
  fs::create_directories(out / "inputs");
  fs::create_directories(out / "tmp");
  const std::string runs_csv = (out / "runs.csv").string();
  const std::string summary_csv = (out / "summary.csv").string();
  const std::string meta_json = (out / "meta.json").string();

  std::vector<RecordedRun> recorded;
  std::set<std::pair<std::string, int>> done;
  if (opt.resume && fs::exists(runs_csv)) {
    const RunsFile file = read_runs(runs_csv, true);
    if (!file.header.empty() && file.header != runs_columns(declaration))
      throw ResultsError(runs_csv + ": its columns differ from this psweep's");
    recorded = recorded_runs(file, runs_csv);
    std::set<std::string> ids;
    for (const auto& run : runs) ids.insert(run.id);
    std::size_t foreign = 0;
    for (const auto& r : recorded) {
      if (!ids.count(r.config_id)) ++foreign;
      done.insert({r.config_id, r.rep});
    }
    if (foreign)
      std::fprintf(stderr,
                   "psweep: warning: %zu rows of %s belong to configurations not in %s (kept, not "
                   "summarized)\n",
                   foreign, runs_csv.c_str(), config.file.c_str());
  } else {
    if (opt.resume)
      std::fprintf(stderr, "psweep: nothing to resume in %s; starting the sweep\n", out.c_str());
    set_aside_previous(out);
  }

  MetaInputs mi{&config, psim, &declaration, opt.command_line, probe_counters(), cores};
  Json meta = build_meta(mi);
  if (shard)
    meta["shard"] = {{"index", shard->index},
                     {"count", shard->count},
                     {"configurations", runs.size()},
                     {"estimate_s", size.total.seconds}};
  if (opt.resume && fs::exists(meta_json)) {
    try {
      Json old = Json::parse(read_file(meta_json));
      if (shard_text(old) != shard_text(meta))
        throw UsageError(fmt::format("{} holds {}, not {}; give each shard its own --out",
                                     out.string(), shard_text(old), shard_text(meta)));
      Json session = {{"date", meta["date"]},
                      {"git", meta["git"]},
                      {"command_line", meta["command_line"]},
                      {"slurm", meta["slurm"]}};
      if (old.contains("config") && old["config"] != meta["config"])
        session["note"] = "the config changed since the sweep started";
      old["resumed"].push_back(session);
      meta = old;
    } catch (const nlohmann::json::exception&) {
      std::fprintf(stderr, "psweep: warning: %s unreadable; writing a new one\n",
                   meta_json.c_str());
    }
  }
  write_json(meta_json, meta);

  std::vector<std::string> inputs(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) {
    if (!runs[i].scene_file.empty()) {
      inputs[i] = runs[i].scene_file;
      continue;
    }
    inputs[i] = (out / "inputs" / (runs[i].id + ".in")).string();
    write_file_atomically(inputs[i], random_scene_input(runs[i].params));
  }

  const auto jobs = make_schedule(runs.size(), config.repetitions, config.warmup, schedule_seed,
                                  [&](std::size_t run, int rep) {
                                    return done.count({runs[run].id, rep}) > 0;
                                  });
  const auto parent_env = current_environment();
  install_interrupt_handlers();
  RowAppender appender(runs_csv, runs_columns(declaration));
  write_summary(summary_csv, runs, recorded);

  Progress progress(jobs, runs.size(), isatty(STDERR_FILENO) == 1);
  const auto sweep_start = std::chrono::steady_clock::now();
  double children_s = 0;
  std::size_t finished = 0, not_ok = 0;
  for (std::size_t j = 0; j < jobs.size() && !interrupt_signal(); ++j) {
    const Job& job = jobs[j];
    const RunSpec& run = runs[job.run];
    progress.start(j, describe(run));
    const std::string metrics =
        (out / "tmp" / fmt::format("{}-{}{}.json", run.id, job.warmup ? "w" : "", job.rep))
            .string();
    fs::remove(metrics);
    std::optional<BusyNeighbour> neighbour;  // lives exactly as long as the run
    if (run.params.neighbour == "busy") neighbour.emplace(BusyNeighbour::last_cpu());
    auto child = run_child(psim_arguments(run, psim, inputs[job.run], metrics),
                           child_environment(run, parent_env), config.timeout_s, &mi.counters);
    neighbour.reset();
    children_s += child.process_s;
    if (child.outcome == Outcome::interrupted) {  // not a result: --resume runs it again
      fs::remove(metrics);
      break;
    }
    std::string metrics_text = fs::exists(metrics) ? read_file(metrics) : std::string();
    fs::remove(metrics);
    Record record =
        make_record(run, job.rep, child, metrics_text, config.timeout_s, cores, declaration);
    progress.finish(j, child.process_s);
    ++finished;
    if (record.status != Status::ok) {
      ++not_ok;
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
  const double sweep_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - sweep_start).count();
  std::error_code ec;
  fs::remove(out / "tmp", ec);  // only when empty

  // The harness's own cost, for the <= 2% budget: everything but the children's lifetimes.
  // harness_cpu_s (psweep's own CPU time) does not depend on how busy the machine is; the wall
  // difference does, because psweep must be scheduled again after each child exits.
  struct rusage self {};
  getrusage(RUSAGE_SELF, &self);
  const double harness_cpu_s =
      static_cast<double>(self.ru_utime.tv_sec + self.ru_stime.tv_sec) +
      static_cast<double>(self.ru_utime.tv_usec + self.ru_stime.tv_usec) / 1e6;
  Json cost = {{"date", utc_now()},
               {"jobs", finished},
               {"sweep_wall_s", sweep_s},
               {"children_process_s", children_s},
               {"overhead", children_s > 0 ? (sweep_s - children_s) / children_s : 0.0},
               {"harness_cpu_s", harness_cpu_s}};
  meta["sessions"].push_back(cost);
  write_json(meta_json, meta);

  std::fprintf(stderr,
               "psweep: %zu runs in %s (harness overhead %.2f%%), %zu not ok; results in %s\n",
               finished, format_duration(sweep_s).c_str(), 100 * cost["overhead"].get<double>(),
               not_ok, out.c_str());
  if (int sig = interrupt_signal()) {
    std::fprintf(stderr,
                 "psweep: interrupted by signal %d; finished rows are kept. Continue with:\n"
                 "  psweep %s --out %s --resume\n",
                 sig, config.file.c_str(), out.c_str());
    return 128 + sig;
  }
  return 0;
}

}  // namespace

int run_sweep(const SweepOptions& opt) {
  try {
    return sweep(opt);
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "psweep: %s\n", e.what());
    return 2;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "psweep: %s\n", e.what());
    return 2;
  } catch (const ResultsError& e) {
    std::fprintf(stderr, "psweep: %s; use another --out\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "psweep: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace psweep
