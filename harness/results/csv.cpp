#include "results/csv.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "particle/io.hpp"
#include "whole_file.hpp"

namespace psweep {
namespace {

[[noreturn]] void io_error(const std::string& what, const std::string& path) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(errno)));
}

std::string number(double v) { return fmt::format("{}", v); }
std::string number(long v) { return fmt::format("{}", v); }

// The columns, each once with its getter: the header and every row come from these tables.
struct ParamColumn {
  const char* name;
  std::string (*cell)(const RunSpec&);
};
constexpr ParamColumn kParamColumns[] = {
    {"config_id", [](const RunSpec& r) { return r.id; }},
    {"engine", [](const RunSpec& r) { return r.params.engine; }},
    {"N", [](const RunSpec& r) { return fmt::format("{}", r.params.N); }},
    {"L", [](const RunSpec& r) { return number(r.params.L); }},
    {"r", [](const RunSpec& r) { return number(r.params.r); }},
    {"S", [](const RunSpec& r) { return fmt::format("{}", r.params.S); }},
    {"slow_factor", [](const RunSpec& r) { return cell(r.params.slow_factor); }},
    {"T", [](const RunSpec& r) { return cell(r.params.T); }},
    {"P", [](const RunSpec& r) { return cell(r.params.P); }},
    {"G", [](const RunSpec& r) { return cell(r.params.G); }},
    {"seed", [](const RunSpec& r) { return cell(r.params.seed); }},
    {"speed_min", [](const RunSpec& r) { return cell(r.params.speed_min); }},
    {"speed_max", [](const RunSpec& r) { return cell(r.params.speed_max); }},
    {"scene_file", [](const RunSpec& r) { return r.scene_file; }},
    {"pin", [](const RunSpec& r) { return std::string(to_string(r.pin)); }},
    {"neighbour", [](const RunSpec& r) { return r.params.neighbour; }},
    {"wall_stop", [](const RunSpec& r) { return r.params.wall_stop; }},
    {"overlap", [](const RunSpec& r) { return r.params.overlap; }},
};

struct RunColumn {
  const char* name;
  std::string (*cell)(const Record&);
};
// A simulated count's cell: empty where the configuration was not simulated.
std::string simulated_cell(const Record& r, std::uint64_t SimulatedCounts::*count) {
  return r.simulated ? fmt::format("{}", (*r.simulated).*count) : std::string();
}
// Before the declared metrics: what psweep itself measured about the child.
constexpr RunColumn kHarnessColumns[] = {
    {"rep", [](const Record& r) { return fmt::format("{}", r.rep); }},
    {"status", [](const Record& r) { return std::string(to_string(r.status)); }},
    {"exit_code", [](const Record& r) { return cell(r.exit_code); }},
    {"wall_s", [](const Record& r) { return cell(r.wall_s()); }},
    {"process_s", [](const Record& r) { return number(r.process_s); }},
    {"user_s", [](const Record& r) { return number(r.user_s); }},
    {"sys_s", [](const Record& r) { return number(r.sys_s); }},
    {"max_rss_kb", [](const Record& r) { return number(r.max_rss_kb); }},
    {"voluntary_switches", [](const Record& r) { return number(r.voluntary_switches); }},
    {"involuntary_switches", [](const Record& r) { return number(r.involuntary_switches); }},
    {"context_switches", [](const Record& r) { return cell(r.events.context_switches); }},
    {"cpu_migrations", [](const Record& r) { return cell(r.events.cpu_migrations); }},
    {"page_faults", [](const Record& r) { return cell(r.events.page_faults); }},
    {"task_clock_s", [](const Record& r) { return cell(r.events.task_clock_s); }},
    {"cycles", [](const Record& r) { return cell(r.events.cycles); }},
    {"instructions", [](const Record& r) { return cell(r.events.instructions); }},
    {"branches", [](const Record& r) { return cell(r.events.branches); }},
    {"branch_misses", [](const Record& r) { return cell(r.events.branch_misses); }},
    {"cache_misses", [](const Record& r) { return cell(r.events.cache_misses); }},
    {"counters_source", [](const Record& r) { return r.counters_source; }},
    {"simulated_instructions",
     [](const Record& r) { return simulated_cell(r, &SimulatedCounts::instructions); }},
    {"simulated_cache_misses",
     [](const Record& r) { return simulated_cell(r, &SimulatedCounts::ll_misses); }},
    {"simulated_branch_misses",
     [](const Record& r) { return simulated_cell(r, &SimulatedCounts::branch_misses); }},
};
// After the declared metrics: the run's identity, an external program's check, the row's error.
constexpr RunColumn kTrailingColumns[] = {
    {"state_hash", [](const Record& r) { return r.metrics ? r.metrics->state_hash : ""; }},
    {"engine_ran", [](const Record& r) { return r.metrics ? r.metrics->engine : ""; }},
    {"node", [](const Record& r) { return r.node; }},
    {"cpus",
     [](const Record& r) {
       if (!r.metrics) return std::string();
       std::set<int> cpus(r.metrics->cpus.begin(), r.metrics->cpus.end());
       return fmt::format("{}", fmt::join(cpus, ";"));
     }},
    {"oversubscribed", [](const Record& r) { return std::string(r.oversubscribed ? "1" : "0"); }},
    {"busy_tasks", [](const Record& r) { return cell(r.busy_tasks); }},
    {"check", [](const Record& r) { return r.check; }},
    {"check_first_step", [](const Record& r) { return r.check_first_step; }},
    {"check_detail", [](const Record& r) { return r.check_detail; }},
    {"error", [](const Record& r) { return r.error; }},
};

// A configuration's summary: its repetitions' figures beside its parameters.
struct Summarized {
  const RunSpec& run;
  const Summary& summary;
};
struct SummaryColumn {
  const char* name;
  std::string (*cell)(const Summarized&);
};
constexpr SummaryColumn kSummaryColumns[] = {
    {"reps", [](const Summarized& s) { return fmt::format("{}", s.summary.reps); }},
    {"failed", [](const Summarized& s) { return fmt::format("{}", s.summary.failed); }},
    {"wall_s_min", [](const Summarized& s) { return cell(s.summary.wall_min); }},
    {"wall_s_median", [](const Summarized& s) { return cell(s.summary.wall_median); }},
    {"wall_s_max", [](const Summarized& s) { return cell(s.summary.wall_max); }},
    {"builds_per_substep", [](const Summarized& s) { return cell(s.summary.builds_per_substep); }},
    {"state_gb_per_s",
     [](const Summarized& s) {
       const Params& p = s.run.params;
       return cell(state_gb_per_s(static_cast<double>(p.N) * static_cast<double>(p.S) *
                                      static_cast<double>(p.slow_factor.value_or(1)),
                                  s.summary.wall_min));
     }},
};

template <class Table>
void add_names(std::vector<std::string>& out, const Table& table) {
  for (const auto& column : table) out.emplace_back(column.name);
}

template <class Table, class Source>
void add_cells(std::vector<std::string>& out, const Table& table, const Source& source) {
  for (const auto& column : table) out.push_back(column.cell(source));
}

}  // namespace

std::vector<std::string> runs_columns(const Declaration& declaration) {
  std::vector<std::string> columns;
  add_names(columns, kParamColumns);
  add_names(columns, kHarnessColumns);
  for (const MetricFacts& m : declaration.metrics) columns.push_back(m.key);
  add_names(columns, kTrailingColumns);
  return columns;
}

std::vector<std::string> summary_columns() {
  std::vector<std::string> columns;
  add_names(columns, kParamColumns);
  add_names(columns, kSummaryColumns);
  return columns;
}

std::string csv_escape(std::string_view f) {
  bool quote = f.find_first_of(",\"\r\n") != std::string_view::npos ||
               (!f.empty() && (f.front() == ' ' || f.back() == ' '));
  if (!quote) return std::string(f);
  std::string out = "\"";
  for (char ch : f) {
    if (ch == '"') out += '"';
    out += ch;
  }
  return out + '"';
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) line += ',';
    line += csv_escape(fields[i]);
  }
  return line + '\n';
}

std::vector<std::string> param_cells(const RunSpec& run) {
  std::vector<std::string> row;
  add_cells(row, kParamColumns, run);
  return row;
}

std::vector<std::string> runs_row(const Record& record, const Declaration& declaration) {
  auto row = param_cells(*record.run);
  add_cells(row, kHarnessColumns, record);
  for (const MetricFacts& m : declaration.metrics)
    row.push_back(record.metrics ? record.metrics->value(m.key) : std::string());
  add_cells(row, kTrailingColumns, record);
  return row;
}

std::vector<std::string> summary_row(const RunSpec& run, const Summary& summary) {
  auto row = param_cells(run);
  add_cells(row, kSummaryColumns, Summarized{run, summary});
  return row;
}

std::vector<std::vector<std::string>> parse_csv(std::string_view text, bool* dropped_partial_line) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string field;
  bool quoted = false;
  bool row_started = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    char ch = text[i];
    row_started = true;
    if (quoted) {
      if (ch == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (ch == '"')
        quoted = false;
      else
        field += ch;
    } else if (ch == '"') {
      quoted = true;
    } else if (ch == ',') {
      row.push_back(std::move(field));
      field.clear();
    } else if (ch == '\n') {
      if (!field.empty() && field.back() == '\r') field.pop_back();
      row.push_back(std::move(field));
      field.clear();
      rows.push_back(std::move(row));
      row.clear();
      row_started = false;
    } else {
      field += ch;
    }
  }
  if (dropped_partial_line) *dropped_partial_line = row_started;
  return rows;
}

void write_file_atomically(const std::string& path, const std::string& content) {
  try {
    lab::WholeFile file(path, "");
    std::fwrite(content.data(), 1, content.size(), file.get());
    file.commit();  // a short write shows as the stream's error, here
  } catch (const particle::InputError& e) {
    throw std::runtime_error(e.what());
  }
}

RowAppender::RowAppender(const std::string& path, const std::vector<std::string>& header)
    : path_(path) {
  bool fresh = !std::filesystem::exists(path) || std::filesystem::file_size(path) == 0;
  file_ = std::fopen(path.c_str(), "ae");  // e: O_CLOEXEC, never inherited by a run
  if (!file_) io_error("cannot open", path);
  if (fresh) append(header);
}

RowAppender::~RowAppender() {
  if (file_) std::fclose(file_);
}

void RowAppender::append(const std::vector<std::string>& row) {
  const std::string line = csv_line(row);
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0)
    io_error("cannot append to", path_);
}

}  // namespace psweep
