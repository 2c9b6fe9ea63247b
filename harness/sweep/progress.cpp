#include "sweep/progress.hpp"

#include <fmt/format.h>

#include <cstdio>

namespace psweep {

void EtaModel::add(std::size_t run, double seconds) {
  sum_[run] += seconds;
  ++count_[run];
  all_sum_ += seconds;
  ++all_count_;
}

double EtaModel::remaining(const std::vector<Job>& jobs, std::size_t next) const {
  if (all_count_ == 0) return 0;
  const double overall = all_sum_ / all_count_;
  double total = 0;
  for (std::size_t i = next; i < jobs.size(); ++i) {
    std::size_t run = jobs[i].run;
    total += count_[run] ? sum_[run] / count_[run] : overall;
  }
  return total;
}

std::string format_duration(double seconds) {
  auto s = static_cast<long long>(seconds + 0.5);
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
  return fmt::format("{}:{:02}", s / 60, s % 60);
}

Progress::Progress(const std::vector<Job>& jobs, std::size_t runs, bool terminal)
    : jobs_(jobs), eta_(runs), terminal_(terminal) {}

void Progress::start(std::size_t index, const std::string& description) {
  double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string eta = index == 0 ? "?" : format_duration(eta_.remaining(jobs_, index));
  const Job& job = jobs_[index];
  std::string what =
      job.warmup ? fmt::format("warm-up {}", job.rep) : fmt::format("rep {}", job.rep);
  std::string line = fmt::format("[{}/{}] elapsed {} eta {} | {} {}", index, jobs_.size(),
                                 format_duration(elapsed), eta, what, description);
  if (terminal_) {
    if (line.size() > 150) line.resize(150);
    std::fprintf(stderr, "\r\033[K%s", line.c_str());
    line_open_ = true;
  } else {
    std::fprintf(stderr, "%s\n", line.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish(std::size_t index, double seconds) { eta_.add(jobs_[index].run, seconds); }

void Progress::note(const std::string& line) {
  if (line_open_) std::fputs("\r\033[K", stderr);
  std::fprintf(stderr, "%s\n", line.c_str());
  line_open_ = false;
}

void Progress::done() {
  if (line_open_) std::fputs("\n", stderr);
  line_open_ = false;
}

}  // namespace psweep
