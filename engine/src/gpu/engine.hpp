#pragma once
// The GPU engine's entry points (engines.cpp): gpu/engine.cu where the build has CUDA
// (PARTICLE_CUDA), gpu/unavailable.cpp where it has not.
#include <string>

#include "particle/options.hpp"
#include "particle/profile.hpp"
#include "step/pipeline.hpp"
#include "world.hpp"

namespace particle::detail::gpu {

// Why this process cannot run the engine ("" when it can): not built with CUDA, or no device.
std::string unavailable();

// A run on the device; throws InputError where its memory cannot hold N.
RunReport run(const World& w, const RunOptions& options, const PipelineParams& params);

}  // namespace particle::detail::gpu
