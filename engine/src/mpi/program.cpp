// The mpi engine from the engine library's side (mpi/engine.hpp): the installed engine where this
// process has it, psim-mpi beside psim where psim delegates it, and otherwise a job of one that
// cannot run it. PARTICLE_WITH_MPI: the build has MPI (and so psim-mpi), set on this file alone.
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "mpi/engine.hpp"

namespace particle {
namespace detail::mpi {
namespace {

std::optional<Installed> installed;
bool delegated = false;  // psim: psim-mpi runs the engine

// psim-mpi beside this process's executable ("" where /proc/self/exe cannot say where that is).
std::string program() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? "" : (self.parent_path() / "psim-mpi").string();
}

const Installed& engine() {
  // simulate() and follow() refuse the engine where unavailable() gives a reason; where it gives
  // none without an installed engine (psim, psim-mpi beside it), psim has entered psim-mpi
  // before (enter_mpi_program): arriving here is a bug.
  if (!installed) throw std::logic_error("engine mpi: run by a process that has not installed it");
  return *installed;
}

}  // namespace

void install(const Installed& e) { installed = e; }

std::string unavailable() {
#ifdef PARTICLE_WITH_MPI
  if (installed) return "";
  if (!delegated)
    return "this program does not run it: psim hands it to psim-mpi, and a program that runs it "
           "itself installs it (install_mpi_engine, particle/processes.hpp)";
  if (const std::string path = program(); path.empty() || access(path.c_str(), X_OK) != 0)
    return "its program " + (path.empty() ? "psim-mpi (/proc/self/exe unreadable)" : path) +
           " is missing (psim runs the engine in psim-mpi beside it: make tools builds both; a "
           "copy of psim needs psim-mpi beside it)";
  return "";
#else
  return "this build has no MPI (PARTICLE_MPI=OFF, or no MPI found: install openmpi-bin and "
         "libopenmpi-dev, as scripts/bootstrap.sh does, and rebuild)";
#endif
}

RunReport run(const World& w, const RunOptions& options, const PipelineParams& params) {
  return engine().lead(w, options, params);
}

RunReport follow(const PipelineParams& own) { return engine().follow(own); }

}  // namespace detail::mpi

using detail::mpi::installed;

void delegate_mpi_engine() { detail::mpi::delegated = true; }

void enter_mpi_program(char** argv) {
  if (installed || !detail::mpi::unavailable().empty()) return;
  const std::string path = detail::mpi::program();
  execv(path.c_str(), argv);
  throw std::runtime_error("cannot start " + path + ": " + std::strerror(errno));
}

// Without the engine installed, a job of one: nothing to join, start, await or call off.
Processes join_processes() { return installed ? installed->join_processes() : Processes{}; }
void start_followers() {
  if (installed) installed->start_followers();
}
std::optional<int> await_leader() { return installed ? installed->await_leader() : 0; }
void call_off(int status) {
  if (installed) installed->call_off(status);
}
void fail_processes(int status) {
  if (installed) installed->fail_processes(status);
}

}  // namespace particle
