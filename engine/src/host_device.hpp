#pragma once
// PARTICLE_HD marks the functions that the CPU engines and the CUDA engine (gpu/) both compile:
// one source of the model's arithmetic, compiled for the host with -ffp-contract=off and for the
// device with --fmad=false, so that both round every operation alike and agree bit for bit.
// The atomics below are the device's where the code runs on it, and plain operations in the
// host's sequential twin of the GPU engine (gpu/host_executor.hpp), which runs one item at a time.
#include <cstdint>

#ifdef __CUDACC__
#define PARTICLE_HD __host__ __device__
#else
#define PARTICLE_HD
#endif

namespace particle::detail {

// Adds v to *at and returns the old value.
PARTICLE_HD inline std::uint32_t fetch_add(std::uint32_t* at, std::uint32_t v) {
#ifdef __CUDA_ARCH__
  return atomicAdd(at, v);
#else
  const std::uint32_t old = *at;
  *at = old + v;
  return old;
#endif
}

PARTICLE_HD inline void store_min(std::uint32_t* at, std::uint32_t v) {
#ifdef __CUDA_ARCH__
  atomicMin(at, v);
#else
  if (v < *at) *at = v;
#endif
}

PARTICLE_HD inline void store_max(unsigned long long* at, unsigned long long v) {
#ifdef __CUDA_ARCH__
  atomicMax(at, v);
#else
  if (v > *at) *at = v;
#endif
}

PARTICLE_HD inline void add_to(unsigned long long* at, unsigned long long v) {
#ifdef __CUDA_ARCH__
  atomicAdd(at, v);
#else
  *at += v;
#endif
}

}  // namespace particle::detail
