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
#include "runner.hpp"
#include "schedule.hpp"
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

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Loads the rows of an existing runs.csv for --resume; drops a partial last line from the file.
std::vector<RecordedRun> load_recorded(const std::string& path,
                                       const std::vector<std::string>& cols) {
  std::string text = read_file(path);
  bool partial = false;
  auto rows = parse_csv(text, &partial);
  if (partial) {
    auto keep = text.rfind('\n');
    keep = keep == std::string::npos ? 0 : keep + 1;
    fs::resize_file(path, keep);
    std::fprintf(stderr, "psweep: %s: dropped an incomplete last line (a write cut short)\n",
                 path.c_str());
  }
  if (rows.empty()) return {};
  if (rows[0] != cols)
    throw UsageError(
        fmt::format("{}: its columns differ from this psweep's; use another --out", path));
  auto index = [&](const char* name) {
    return static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin());
  };
  const std::size_t id_col = index("config_id"), rep_col = index("rep"),
                    status_col = index("status"), wall_col = index("wall_s");
  std::vector<RecordedRun> runs;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& row = rows[i];
    if (row.size() != cols.size())
      throw UsageError(fmt::format("{}: line {} has {} fields, expected {}", path, i + 1,
                                   row.size(), cols.size()));
    RecordedRun r;
    r.config_id = row[id_col];
    r.ok = row[status_col] == "ok";
    try {
      r.rep = std::stoi(row[rep_col]);
      if (!row[wall_col].empty()) r.wall_s = std::stod(row[wall_col]);
    } catch (const std::logic_error&) {
      throw UsageError(fmt::format("{}: line {}: rep or wall_s is not a number", path, i + 1));
    }
    runs.push_back(std::move(r));
  }
  return runs;
}

void write_summary(const std::string& path, const std::vector<RunSpec>& runs,
                   const std::vector<RecordedRun>& recorded) {
  std::string text = csv_line(summary_columns());
  for (const auto& run : runs) text += csv_line(summary_row(run, summarize(recorded, run.id)));
  write_file_atomically(path, text);
}

void write_json(const std::string& path, const Json& j) {
  write_file_atomically(path, j.dump(2) + "\n");
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
  std::vector<RunSpec> runs = expand(config, declaration);
  const int cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));

  if (opt.dry_run) {
    for (const auto& run : runs) std::printf("%s\n", describe(run).c_str());
    std::printf(
        "%zu configurations x %d repetitions = %zu runs (+ %zu warm-up runs), pin %s, timeout %g "
        "s\n",
        runs.size(), config.repetitions, runs.size() * static_cast<std::size_t>(config.repetitions),
        runs.size() * static_cast<std::size_t>(config.warmup), to_string(config.pin),
        config.timeout_s);
    if (!psim_ok) {
      std::fprintf(stderr,
                   "psweep: warning: %s not found; engine names not checked and no axis left out "
                   "(psim --describe says which parameters each engine uses)\n",
                   psim.c_str());
    }
    return 0;
  }
  if (!psim_ok)
    throw UsageError(
        fmt::format("psim not found or not executable: {} (use --psim PATH or PSIM=)", psim));

  const fs::path out = opt.out_dir.value_or("results/" + config.name);
  fs::create_directories(out / "inputs");
  fs::create_directories(out / "tmp");
  const std::string runs_csv = (out / "runs.csv").string();
  const std::string summary_csv = (out / "summary.csv").string();
  const std::string meta_json = (out / "meta.json").string();

  std::vector<RecordedRun> recorded;
  std::set<std::pair<std::string, int>> done;
  if (opt.resume && fs::exists(runs_csv)) {
    recorded = load_recorded(runs_csv, runs_columns(declaration));
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
  if (opt.resume && fs::exists(meta_json)) {
    try {
      Json old = Json::parse(read_file(meta_json));
      Json session = {
          {"date", meta["date"]}, {"git", meta["git"]}, {"command_line", meta["command_line"]}};
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
  } catch (const std::exception& e) {
    std::fprintf(stderr, "psweep: error: %s\n", e.what());
    return 1;
  }
}

}  // namespace psweep
