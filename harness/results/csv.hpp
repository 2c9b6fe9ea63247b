// CSV: the runs.csv and summary.csv formats, and the minimal RFC 4180 reader that --resume needs.
//
// Fields are quoted only when they must be (comma, quote, CR/LF, leading/trailing space), quotes
// doubled inside. Numbers use the shortest text that reads back to the same double. An empty cell
// means "does not apply or not available", never zero.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "results/stats.hpp"
#include "run/record.hpp"

namespace psweep {

// runs.csv: the parameters, what psweep measured, one column per metric psim declares (in its
// order), then the run's identity and verdict.
std::vector<std::string> runs_columns(const Declaration& declaration);
std::vector<std::string> summary_columns();

std::string csv_escape(std::string_view field);
std::string csv_line(const std::vector<std::string>& fields);  // ends with '\n'

// The parameter cells shared by both files: config_id ... pin.
std::vector<std::string> param_cells(const RunSpec& run);
std::vector<std::string> runs_row(const Record& record, const Declaration& declaration);
std::vector<std::string> summary_row(const RunSpec& run, const Summary& summary);

// Parses CSV text. A last line without its newline (a write cut short) is dropped and reported
// through `dropped_partial_line`.
std::vector<std::vector<std::string>> parse_csv(std::string_view text,
                                                bool* dropped_partial_line = nullptr);

// Writes `content` to `path` through a temporary file and rename(): readers see the old or the
// new file, never half of one; a link's target is written, a device or FIFO in place
// (lab::WholeFile, as psim writes its files). Throws std::runtime_error on I/O errors, the
// temporary removed.
void write_file_atomically(const std::string& path, const std::string& content);

// runs.csv: one line appended and flushed per run, so a crash or interrupt loses no finished row.
class RowAppender {
 public:
  // Opens `path` for appending; writes `header` when the file is new or empty.
  RowAppender(const std::string& path, const std::vector<std::string>& header);
  ~RowAppender();
  RowAppender(const RowAppender&) = delete;
  RowAppender& operator=(const RowAppender&) = delete;
  void append(const std::vector<std::string>& row);

 private:
  std::FILE* file_ = nullptr;
  std::string path_;
};

}  // namespace psweep
