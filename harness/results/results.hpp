// Results folder: reading back runs.csv and writing summary.csv and meta.json, for the sweep
// (its --resume) and for merging shards, so both read and write the files the same way.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "config/expansion.hpp"
#include "results/stats.hpp"

namespace psweep {

// A results file that cannot be used (wrong columns, a malformed row): exit status 2.
struct ResultsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A runs.csv as read back. Its header, not this psweep's columns, says where each field is, so
// shards written by the same build merge whatever their columns.
struct RunsFile {
  std::vector<std::string> header;  // empty for an empty file
  std::vector<std::vector<std::string>> rows;
};

// Reads `path`; throws ResultsError for a row of another width than the header's. A partial last
// line (a write cut short) is dropped, and cut from the file too when `repair` is set.
RunsFile read_runs(const std::string& path, bool repair);

// The index of column `name`; throws ResultsError naming `path` when the header lacks it.
std::size_t column(const RunsFile& file, const std::string& name, const std::string& path);

// What the summary needs from each row; throws ResultsError naming the line.
std::vector<RecordedRun> recorded_runs(const RunsFile& file, const std::string& path);

// One summary.csv row per configuration of `runs`, in their order.
void write_summary(const std::string& path, const std::vector<RunSpec>& runs,
                   const std::vector<RecordedRun>& recorded);

void write_json(const std::string& path, const Json& json);

}  // namespace psweep
