#include "csv.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace psweep {
namespace {

template <class T>
std::string cell(const std::optional<T>& v) {
  return v ? fmt::format("{}", *v) : std::string();
}

[[noreturn]] void io_error(const std::string& what, const std::string& path) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(errno)));
}

}  // namespace

const std::vector<std::string>& runs_columns() {
  static const std::vector<std::string> columns = {"config_id",
                                                   "engine",
                                                   "N",
                                                   "L",
                                                   "r",
                                                   "S",
                                                   "slow_factor",
                                                   "T",
                                                   "G",
                                                   "seed",
                                                   "speed_min",
                                                   "speed_max",
                                                   "scene_file",
                                                   "pin",
                                                   "rep",
                                                   "status",
                                                   "exit_code",
                                                   "wall_s",
                                                   "process_s",
                                                   "user_s",
                                                   "sys_s",
                                                   "max_rss_kb",
                                                   "voluntary_switches",
                                                   "involuntary_switches",
                                                   "context_switches",
                                                   "cpu_migrations",
                                                   "page_faults",
                                                   "task_clock_s",
                                                   "cycles",
                                                   "instructions",
                                                   "branches",
                                                   "branch_misses",
                                                   "cache_misses",
                                                   "broad_phase_s",
                                                   "narrow_phase_s",
                                                   "order_s",
                                                   "filter_s",
                                                   "resolve_s",
                                                   "advance_s",
                                                   "pair_tests",
                                                   "candidates",
                                                   "pair_collisions",
                                                   "wall_collisions",
                                                   "dropped",
                                                   "overlaps",
                                                   "energy_initial",
                                                   "energy_final",
                                                   "state_hash",
                                                   "engine_ran",
                                                   "cpus",
                                                   "oversubscribed",
                                                   "error"};
  return columns;
}

const std::vector<std::string>& summary_columns() {
  static const std::vector<std::string> columns = {
      "config_id",   "engine", "N",    "L",      "r",          "S",
      "slow_factor", "T",      "G",    "seed",   "speed_min",  "speed_max",
      "scene_file",  "pin",    "reps", "failed", "wall_s_min", "wall_s_median",
      "wall_s_max"};
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
  const auto& p = run.params;
  return {run.id,
          p.engine,
          fmt::format("{}", p.N),
          fmt::format("{}", p.L),
          fmt::format("{}", p.r),
          fmt::format("{}", p.S),
          cell(p.slow_factor),
          cell(p.T),
          cell(p.G),
          cell(p.seed),
          cell(p.speed_min),
          cell(p.speed_max),
          run.scene_file,
          to_string(run.pin)};
}

std::vector<std::string> runs_row(const Record& r) {
  auto row = param_cells(*r.run);
  const auto& e = r.events;
  auto add = [&](std::string s) { row.push_back(std::move(s)); };
  add(fmt::format("{}", r.rep));
  add(to_string(r.status));
  add(cell(r.exit_code));
  add(r.metrics ? cell(r.metrics->wall_s) : "");
  add(fmt::format("{}", r.process_s));
  add(fmt::format("{}", r.user_s));
  add(fmt::format("{}", r.sys_s));
  add(fmt::format("{}", r.max_rss_kb));
  add(fmt::format("{}", r.voluntary_switches));
  add(fmt::format("{}", r.involuntary_switches));
  for (const auto& v : {e.context_switches, e.cpu_migrations, e.page_faults}) add(cell(v));
  add(cell(e.task_clock_s));
  for (const auto& v : {e.cycles, e.instructions, e.branches, e.branch_misses, e.cache_misses})
    add(cell(v));
  const Metrics empty;
  const Metrics& m = r.metrics ? *r.metrics : empty;
  for (const auto& v : m.stages) add(cell(v));
  for (const auto& v : m.counters) add(cell(v));
  add(cell(m.energy_initial));
  add(cell(m.energy_final));
  add(m.state_hash);
  add(m.engine);
  std::set<int> cpus(m.cpus.begin(), m.cpus.end());
  add(fmt::format("{}", fmt::join(cpus, ";")));
  add(r.oversubscribed ? "1" : "0");
  add(r.error);
  return row;
}

std::vector<std::string> summary_row(const RunSpec& run, const Summary& s) {
  auto row = param_cells(run);
  row.push_back(fmt::format("{}", s.reps));
  row.push_back(fmt::format("{}", s.failed));
  row.push_back(cell(s.wall_min));
  row.push_back(cell(s.wall_median));
  row.push_back(cell(s.wall_max));
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
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) io_error("cannot write", tmp);
  bool ok = std::fwrite(content.data(), 1, content.size(), f) == content.size();
  ok = (std::fclose(f) == 0) && ok;
  if (!ok) io_error("cannot write", tmp);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) io_error("cannot rename to", path);
}

RowAppender::RowAppender(const std::string& path) : path_(path) {
  bool fresh = !std::filesystem::exists(path) || std::filesystem::file_size(path) == 0;
  file_ = std::fopen(path.c_str(), "a");
  if (!file_) io_error("cannot open", path);
  if (fresh) append(runs_columns());
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
