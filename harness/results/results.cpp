// Results folder: see results.hpp.
#include "results/results.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

#include "results/csv.hpp"

namespace fs = std::filesystem;

namespace psweep {

RunsFile read_runs(const std::string& path, bool repair) {
  std::string text = read_file(path);
  bool partial = false;
  auto rows = parse_csv(text, &partial);
  if (partial) {
    if (repair) {
      auto keep = text.rfind('\n');
      keep = keep == std::string::npos ? 0 : keep + 1;
      fs::resize_file(path, keep);
    }
    std::fprintf(stderr, "psweep: %s: %s an incomplete last line (a write cut short)\n",
                 path.c_str(), repair ? "dropped" : "ignored");
  }
  RunsFile file;
  if (rows.empty()) return file;
  file.header = std::move(rows[0]);
  file.rows.assign(std::make_move_iterator(rows.begin() + 1), std::make_move_iterator(rows.end()));
  for (std::size_t i = 0; i < file.rows.size(); ++i)
    if (file.rows[i].size() != file.header.size())
      throw ResultsError(fmt::format("{}: line {} has {} fields, expected {}", path, i + 2,
                                     file.rows[i].size(), file.header.size()));
  return file;
}

namespace {
std::optional<std::size_t> find_column(const RunsFile& file, const std::string& name) {
  const auto it = std::find(file.header.begin(), file.header.end(), name);
  if (it == file.header.end()) return std::nullopt;
  return static_cast<std::size_t>(it - file.header.begin());
}
}  // namespace

std::size_t column(const RunsFile& file, const std::string& name, const std::string& path) {
  const auto found = find_column(file, name);
  if (!found)
    throw ResultsError(fmt::format("{}: no column {}; not a runs.csv of psweep", path, name));
  return *found;
}

std::vector<RecordedRun> recorded_runs(const RunsFile& file, const std::string& path) {
  std::vector<RecordedRun> runs;
  if (file.header.empty()) return runs;
  const std::size_t id_col = column(file, "config_id", path), rep_col = column(file, "rep", path),
                    status_col = column(file, "status", path),
                    wall_col = column(file, "wall_s", path),
                    check_col = column(file, "check", path);
  // Optional: a runs.csv from before the metric has no builds.
  const auto builds_col = find_column(file, "broad_phase_builds"),
             reached_col = find_column(file, "time_reached"),
             k_col = find_column(file, "slow_factor");
  runs.reserve(file.rows.size());
  for (std::size_t i = 0; i < file.rows.size(); ++i) {
    const auto& row = file.rows[i];
    RecordedRun r;
    r.config_id = row[id_col];
    r.ok = row[status_col] == "ok";
    r.checked = !row[check_col].empty();
    try {
      r.rep = std::stoi(row[rep_col]);
      if (!row[wall_col].empty()) r.wall_s = std::stod(row[wall_col]);
    } catch (const std::logic_error&) {
      throw ResultsError(fmt::format("{}: line {}: rep or wall_s is not a number", path, i + 2));
    }
    if (builds_col && reached_col) {
      std::optional<std::int64_t> k;
      if (k_col && !row[*k_col].empty()) k = std::atoll(row[*k_col].c_str());
      r.builds_per_substep = builds_per_substep(row[*builds_col], row[*reached_col], k);
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

}  // namespace psweep
