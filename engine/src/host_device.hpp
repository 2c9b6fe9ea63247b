#pragma once
// PARTICLE_HD marks the functions that the CPU engines and the CUDA engine (gpu/) both compile:
// one source of the model's arithmetic, compiled for the host with -ffp-contract=off and for the
// device with --fmad=false, so that both round every operation alike and agree bit for bit.
//
// The atomics below are the device's where the code runs on it, and plain operations in the
// host's sequential twin of the GPU engine (gpu/host_executor.hpp), which runs one item at a
// time. Those on one shared counter (claim, add_to, store_max: every thread that calls them at
// once passes the same address) combine the calls of a warp first and make one atomic per warp:
// a million threads on one address would otherwise queue behind each other.
#include <cstdint>

#ifdef __CUDACC__
#define PARTICLE_HD __host__ __device__
#include <cooperative_groups.h>
#include <cooperative_groups/reduce.h>
#else
#define PARTICLE_HD
#endif

namespace particle::detail {

// Adds 1 to *at and returns the old value: the count of a cell, its own address per thread.
PARTICLE_HD inline std::uint32_t fetch_add(std::uint32_t* at) {
#ifdef __CUDA_ARCH__
  return atomicAdd(at, 1u);
#else
  return (*at)++;
#endif
}

// The next free slot of a list whose length is *size (one counter for every caller).
PARTICLE_HD inline std::uint32_t claim(std::uint32_t* size) {
#ifdef __CUDA_ARCH__
  namespace cg = cooperative_groups;
  const cg::coalesced_group warp = cg::coalesced_threads();
  std::uint32_t first = 0;
  if (warp.thread_rank() == 0) first = atomicAdd(size, warp.num_threads());
  return warp.shfl(first, 0) + warp.thread_rank();
#else
  return (*size)++;
#endif
}

// *at = min(*at, v), each thread its own address (a particle's best rank).
PARTICLE_HD inline void store_min(std::uint32_t* at, std::uint32_t v) {
#ifdef __CUDA_ARCH__
  atomicMin(at, v);
#else
  if (v < *at) *at = v;
#endif
}

#ifdef __CUDA_ARCH__
// The values of the warp's calling threads combined by `op`, handed to `apply` on one of them.
template <class Op, class Apply>
__device__ void once_per_warp(unsigned long long v, Op op, Apply apply) {
  namespace cg = cooperative_groups;
  const cg::coalesced_group warp = cg::coalesced_threads();
  const unsigned long long combined = cg::reduce(warp, v, op);
  if (warp.thread_rank() == 0) apply(combined);
}
#endif

// *at = max(*at, v), one address for every caller.
PARTICLE_HD inline void store_max(unsigned long long* at, unsigned long long v) {
#ifdef __CUDA_ARCH__
  once_per_warp(v, cooperative_groups::greater<unsigned long long>(),
                [at](unsigned long long most) { atomicMax(at, most); });
#else
  if (v > *at) *at = v;
#endif
}

// *at += v, one address for every caller.
PARTICLE_HD inline void add_to(unsigned long long* at, unsigned long long v) {
#ifdef __CUDA_ARCH__
  once_per_warp(v, cooperative_groups::plus<unsigned long long>(),
                [at](unsigned long long sum) { atomicAdd(at, sum); });
#else
  *at += v;
#endif
}

}  // namespace particle::detail
