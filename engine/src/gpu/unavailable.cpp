// The GPU engine in a build without CUDA (PARTICLE_CUDA=OFF, or AUTO where CMake found no nvcc):
// declared like every engine, refused with the reason when asked to run.
#include "gpu/engine.hpp"
#include "particle/io.hpp"

namespace particle::detail::gpu {

std::string unavailable() {
  return "this build has no CUDA (PARTICLE_CUDA=OFF, or no nvcc found: put it on PATH or set "
         "CUDA_HOME, and rebuild)";
}

// simulate() asks unavailable() first; a caller that did not still gets the reason.
RunReport run(const World&, const RunOptions&, const PipelineParams&) {
  throw InputError("engine gpu: " + unavailable());
}

}  // namespace particle::detail::gpu
