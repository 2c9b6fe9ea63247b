// particle/processes.hpp with MPI: the job is MPI_COMM_WORLD; the leader's first broadcast is a
// word saying whether the followers follow (the engine then sends their share) or end, and how.
// install_mpi_engine hands these and the engine's run to the engine library (mpi/program.cpp).
#include "particle/processes.hpp"

#include <mpi.h>

#include <stdexcept>

#include "mpi/comm.hpp"
#include "mpi/engine.hpp"

namespace particle {
namespace detail::mpi {
namespace {

// MPI for the process's life: initialised on first use unless someone else did, and then
// finalised when the process ends (main has returned; no thread of the engine runs then).
class Session {
 public:
  Session() {
    int ready;
    MPI_Initialized(&ready);
    if (ready) return;
    int provided;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    started_ = true;
    // The engine calls MPI from each rank's main thread alone, between its OpenMP teams.
    if (provided < MPI_THREAD_FUNNELED)
      throw std::runtime_error(
          "MPI: this implementation cannot be called beside OpenMP threads "
          "(MPI_THREAD_FUNNELED not provided)");
  }
  ~Session() {
    int done;
    MPI_Finalized(&done);
    if (started_ && !done) MPI_Finalize();
  }

 private:
  bool started_ = false;
};

// The leader's word to its followers: follow, or the status to end with.
constexpr int kFollow = -1;
bool started = false;  // this process has sent or received the word

// Whether this process joined a job of several (join_processes): the functions below do nothing
// otherwise, so a run of another engine never starts MPI.
bool in_job_of_several() {
  int ready;
  MPI_Initialized(&ready);
  return ready && rank_count() > 1;
}

void send_word(int word) {
  MPI_Bcast(&word, 1, MPI_INT, 0, MPI_COMM_WORLD);
  started = true;
}

Processes join_processes() {
  static Session session;
  return {this_rank(), rank_count()};
}

void start_followers() {
  if (in_job_of_several()) send_word(kFollow);
}

std::optional<int> await_leader() {
  int word;
  MPI_Bcast(&word, 1, MPI_INT, 0, MPI_COMM_WORLD);
  started = true;
  if (word == kFollow) return std::nullopt;
  return word;
}

void call_off(int status) {
  if (!in_job_of_several() || started || this_rank() != 0) return;
  send_word(status);
}

void fail_processes(int status) {
  if (!in_job_of_several()) return;
  if (!started) return call_off(status);  // the leader; a follower fails only once started
  MPI_Abort(MPI_COMM_WORLD, status);
}

constexpr Installed kEngine{lead,         follow_leader, join_processes, start_followers,
                            await_leader, call_off,      fail_processes};

}  // namespace
}  // namespace detail::mpi

void install_mpi_engine() { detail::mpi::install(detail::mpi::kEngine); }

}  // namespace particle
