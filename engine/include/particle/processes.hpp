#pragma once
// The processes that run one simulation together: the mpi engine's ranks, started by a launcher
// (`mpirun -np P psim --engine mpi SCENE`, docs/engines.md). Rank 0 leads: it reads the scene,
// shares it, and alone writes; the others follow, run their share and write nothing. Without a
// launcher, and in a build without MPI, there is one process, which leads.
#include <variant>

#include "particle/scene.hpp"

namespace particle {

struct Processes {
  int rank = 0;
  int count = 1;
  bool leads() const { return rank == 0; }
};

// Joins the launcher's job (MPI, initialised once per process and finalised when it ends; a
// process started without a launcher is a job of one). {0, 1} in a build without MPI.
Processes join_processes();

// The leader: its scene to every follower, which then runs it too. Once per process.
void share_scene(const Scene& scene);

// A follower: the leader's scene, or the exit status the leader ended with before sharing one
// (call_off).
std::variant<Scene, int> await_scene();

// The leader, when it ends without sharing a scene (--write-scene, an error): the followers end
// with `status`. Nothing once the scene is shared, and nothing without followers.
void call_off(int status);

// A process that fails with `status`: before the leader shared the scene, as call_off; after it,
// the others may wait for this one in a collective that never comes, so every process of the job
// ends at once with `status` (MPI_Abort). Returns only where it has nothing to do.
void fail_processes(int status);

}  // namespace particle
