#pragma once
// The MPI engine's entry points. Its code and MPI's libraries are linked into psim-mpi alone (the
// particle_mpi library: every mpi/*.cpp but program.cpp), so that psim and every other program
// start without loading MPI (docs/architecture.md, "The mpi engine's program"). The engine
// library's side, mpi/program.cpp, answers for the engine in every process: it calls the engine
// where the process installed it (install_mpi_engine: psim-mpi, the tests that run it), and psim
// hands a run of it over to psim-mpi (enter_mpi_program).
#include <optional>
#include <string>

#include "particle/options.hpp"
#include "particle/processes.hpp"
#include "particle/profile.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail::mpi {

// The engine as a process that has it installs it (mpi/processes.cpp).
struct Installed {
  RunReport (*lead)(const World&, const RunOptions&, const PipelineParams&);
  RunReport (*follow)(const PipelineParams&);
  Processes (*join_processes)();  // particle/processes.hpp's functions, with MPI
  void (*start_followers)();
  std::optional<int> (*await_leader)();
  void (*call_off)(int);
  void (*fail_processes)(int);
};
void install(const Installed& engine);

// Why this process cannot run the engine ("" when it can, or when psim-mpi beside psim can).
std::string unavailable();

// Rank 0's run over every rank of the job (particle/processes.hpp), from simulate(): it sends each
// rank its share of w and returns w with the final state and the run's report; it alone calls
// params.on_time_unit. The installed engine's (mpi/engine.cpp's lead), or InputError.
RunReport run(const World& w, const RunOptions& options, const PipelineParams& params);

// Another rank's share of rank 0's run, from particle::follow: the run's World, steps and slow
// factor are rank 0's (threads, profile and stop are this rank's own, in `own`). Its report
// counts nothing: rank 0's has the run's counters. The installed engine's, or InputError.
RunReport follow(const PipelineParams& own);

// mpi/engine.cpp (particle_mpi): run and follow where the engine is installed.
RunReport lead(const World& w, const RunOptions& options, const PipelineParams& params);
RunReport follow_leader(const PipelineParams& own);

}  // namespace particle::detail::mpi
