#pragma once
// The processes that run one simulation together: the mpi engine's ranks, started by a launcher
// (`mpirun -np P psim --engine mpi SCENE`, docs/engines.md). Rank 0 leads: it reads the scene,
// runs simulate() on it, sends each follower its share, and alone writes; the others follow
// (particle::follow, simulation.hpp), hold their share alone and write nothing. Without a
// launcher, in a build without MPI and in a process without the engine, there is one process,
// which leads.
//
// The engine and MPI's libraries are linked into one program alone, psim-mpi, beside psim: psim
// and every other program start without loading them (docs/architecture.md, "The mpi engine's
// program"). psim-mpi installs the engine (install_mpi_engine) before anything else; psim
// delegates it (delegate_mpi_engine): `psim --engine mpi` becomes psim-mpi with the same arguments
// (enter_mpi_program), and the engine is available to psim where psim-mpi is beside it.
#include <optional>

namespace particle {

// psim-mpi and the tests that run the engine in process: this process runs it (particle_mpi, the
// library of a build with MPI).
void install_mpi_engine();

// psim: the engine is psim-mpi's, found beside this program's executable (its real path: not the
// working directory, and the same in the build folder, a device kit or a copy of both).
void delegate_mpi_engine();

// psim, for a run of the mpi engine: replaces this process by psim-mpi with the same arguments
// (never returns; std::runtime_error where the exec fails). Returns at once where the engine is
// installed, and where it is unavailable (engine_unavailable("mpi") then says why).
void enter_mpi_program(char** argv);

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
