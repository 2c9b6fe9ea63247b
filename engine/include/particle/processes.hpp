#pragma once
// The processes that run one simulation together: the mpi engine's ranks, started by a launcher
// (`mpirun -np P psim --engine mpi SCENE`, docs/engines.md). Rank 0 leads: it reads the scene,
// runs simulate() on it, sends each follower its share, and alone writes; the others follow
// (particle::follow, simulation.hpp), hold their share alone and write nothing. Without a
// launcher, and in a build without MPI, there is one process, which leads.
#include <optional>

namespace particle {

struct Processes {
  int rank = 0;
  int count = 1;
  bool leads() const { return rank == 0; }
};

// Joins the launcher's job (MPI, initialised once per process and finalised when it ends; a
// process started without a launcher is a job of one). {0, 1} in a build without MPI.
Processes join_processes();

// The leader, once it has a scene to run: the followers are told to follow. Once per process.
void start_followers();

// A follower: nothing once the leader started the followers (then particle::follow), or the exit
// status the leader ended with before it did (call_off).
std::optional<int> await_leader();

// The leader, when it ends without starting the followers (--write-scene, an error): they end
// with `status`. Nothing once they are started, and nothing without followers.
void call_off(int status);

// A process that fails with `status`: before the leader started the followers, as call_off; after,
// the others may wait for this one in a collective that never comes, so every process of the job
// ends at once with `status` (MPI_Abort). Returns only where it has nothing to do.
void fail_processes(int status);

}  // namespace particle
