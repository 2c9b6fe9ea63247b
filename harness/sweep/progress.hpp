// Progress: "[done/total] elapsed, ETA, current run" on stderr; one updating line on a terminal,
// plain lines otherwise. The ETA sums, over the jobs still to run, the mean time observed for
// that configuration (or the mean over all runs when the configuration has not run yet), so a
// sweep whose sizes differ by 100x still gets a sensible estimate after its first round.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <vector>

#include "sweep/schedule.hpp"

namespace psweep {

class EtaModel {
 public:
  explicit EtaModel(std::size_t runs) : sum_(runs, 0.0), count_(runs, 0) {}
  void add(std::size_t run, double seconds);
  // Expected seconds of the jobs [next, end) of `jobs`; 0 before anything was observed.
  double remaining(const std::vector<Job>& jobs, std::size_t next) const;

 private:
  std::vector<double> sum_;
  std::vector<int> count_;
  double all_sum_ = 0;
  int all_count_ = 0;
};

// "1:05:09" / "4:07"
std::string format_duration(double seconds);

class Progress {
 public:
  Progress(const std::vector<Job>& jobs, std::size_t runs, bool terminal);
  void start(std::size_t index, const std::string& description);  // job `index` begins
  void finish(std::size_t index, double seconds);                 // job `index` ended
  void note(const std::string& line);                             // a message between updates
  void done();                                                    // ends the updating line

 private:
  const std::vector<Job>& jobs_;
  EtaModel eta_;
  bool terminal_;
  bool line_open_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace psweep
