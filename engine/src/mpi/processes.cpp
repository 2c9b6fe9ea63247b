// particle/processes.hpp with MPI: the job is MPI_COMM_WORLD; the leader shares its scene with a
// broadcast that starts with a word saying whether a scene follows or the status to end with.
#include "particle/processes.hpp"

#include <mpi.h>

#include <cstdint>
#include <stdexcept>

#include "mpi/comm.hpp"

namespace particle {
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

// The first word of the leader's broadcast: a scene follows, or the status to end with.
constexpr int kSceneFollows = -1;
bool shared = false;  // this process has sent or received the first word

struct Header {
  double L, r;
  std::int64_t steps;
  std::uint64_t n;
  int print, generated;
};

template <class T>
void broadcast(std::vector<T>& values) {
  MPI_Bcast(values.data(), static_cast<int>(values.size()), detail::mpi::record_type<T>(), 0,
            MPI_COMM_WORLD);
}

void broadcast_particles(Particles& p) {
  broadcast(p.x);
  broadcast(p.y);
  broadcast(p.vx);
  broadcast(p.vy);
  broadcast(p.pair_collisions);
  broadcast(p.wall_collisions);
}

// Whether this process joined a job of several (join_processes): the functions below do nothing
// otherwise, so a run of another engine never starts MPI.
bool in_job_of_several() {
  int ready;
  MPI_Initialized(&ready);
  return ready && detail::mpi::rank_count() > 1;
}

void send_first_word(int word) {
  MPI_Bcast(&word, 1, MPI_INT, 0, MPI_COMM_WORLD);
  shared = true;
}

}  // namespace

Processes join_processes() {
  static Session session;
  return {detail::mpi::this_rank(), detail::mpi::rank_count()};
}

void share_scene(const Scene& scene) {
  if (!in_job_of_several()) return;
  send_first_word(kSceneFollows);
  Header h{scene.L,
           scene.r,
           scene.steps,
           scene.size(),
           scene.mode == OutputMode::print ? 1 : 0,
           scene.generated ? 1 : 0};
  MPI_Bcast(&h, 1, detail::mpi::record_type<Header>(), 0, MPI_COMM_WORLD);
  Particles copy = scene.particles;  // MPI_Bcast's buffer is not const, even at its root
  broadcast_particles(copy);
}

std::variant<Scene, int> await_scene() {
  int word;
  MPI_Bcast(&word, 1, MPI_INT, 0, MPI_COMM_WORLD);
  shared = true;
  if (word != kSceneFollows) return word;
  Header h;
  MPI_Bcast(&h, 1, detail::mpi::record_type<Header>(), 0, MPI_COMM_WORLD);
  Scene scene;
  scene.L = h.L;
  scene.r = h.r;
  scene.steps = h.steps;
  scene.mode = h.print ? OutputMode::print : OutputMode::perf;
  scene.generated = h.generated != 0;
  scene.particles = Particles(h.n);
  broadcast_particles(scene.particles);
  return scene;
}

void call_off(int status) {
  if (!in_job_of_several() || shared || detail::mpi::this_rank() != 0) return;
  send_first_word(status);
}

void fail_processes(int status) {
  if (!in_job_of_several()) return;
  if (!shared) return call_off(status);  // the leader; a follower fails only once it has a scene
  MPI_Abort(MPI_COMM_WORLD, status);
}

}  // namespace particle
