#include "startup.hpp"

#include <fcntl.h>
#include <omp.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

#include "run/runner.hpp"

extern char** environ;

namespace ceilings {
namespace {

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// One parallel region whose threads each say they joined: GCC drops an empty region, and the
// count checks that the team had every thread asked for.
void region(int threads) {
  std::atomic<int> joined{0};
#pragma omp parallel num_threads(threads)
  joined.fetch_add(1, std::memory_order_relaxed);
  if (joined.load() != threads)
    throw std::runtime_error("an OpenMP team of " + std::to_string(joined.load()) +
                             " threads, not " + std::to_string(threads));
}

// The file actions of a child whose output is not measured (psim's states): stdout to /dev/null.
class QuietStdout {
 public:
  QuietStdout() {
    posix_spawn_file_actions_init(&actions_);
    posix_spawn_file_actions_addopen(&actions_, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  }
  ~QuietStdout() { posix_spawn_file_actions_destroy(&actions_); }
  QuietStdout(const QuietStdout&) = delete;
  QuietStdout& operator=(const QuietStdout&) = delete;
  const posix_spawn_file_actions_t* get() const { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_;
};

}  // namespace

std::vector<double> time_processes(const std::vector<std::string>& argv, int repetitions) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const QuietStdout quiet;
  std::vector<double> seconds;
  for (int rep = 0; rep < repetitions; ++rep) {
    const double start = now_s();
    pid_t pid = 0;
    if (posix_spawn(&pid, args[0], quiet.get(), nullptr, args.data(), environ) != 0)
      throw std::runtime_error("cannot start " + argv[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    seconds.push_back(now_s() - start);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
      throw std::runtime_error(argv[0] + " failed");
  }
  return seconds;
}

double first_team_s(int threads) {
  const double start = omp_get_wtime();
  region(threads);
  return omp_get_wtime() - start;
}

double warm_region_s(int threads, int regions) {
  region(threads);
  const double start = omp_get_wtime();
  for (int k = 0; k < regions; ++k) region(threads);
  return (omp_get_wtime() - start) / regions;
}

std::vector<double> child_figures(const std::vector<std::string>& argv, int repetitions) {
  std::vector<double> figures;
  for (int rep = 0; rep < repetitions; ++rep) {
    const auto out = psweep::capture_output(argv);
    if (!out) throw std::runtime_error(argv[0] + " --team failed");
    figures.push_back(std::stod(*out));
  }
  return figures;
}

}  // namespace ceilings
