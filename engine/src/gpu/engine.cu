// The GPU engine: gpu/parallel_step.hpp's sub-step on a CUDA device. Each stage function runs as
// one thread per index; sorts and scans are CUB's; the state stays on the device for the whole
// run and comes back for each printed time unit and at the end. (No fmt here: its compile-time
// format checks are consteval, which nvcc 13 cannot evaluate.)
#include <cuda_runtime.h>

#include <cstdlib>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "gpu/engine.hpp"
#include "gpu/parallel_step.hpp"
#include "particle/io.hpp"

namespace particle::detail::gpu {
namespace {

void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess)
    throw std::runtime_error(std::string("gpu: ") + what + ": " + cudaGetErrorString(status));
}

constexpr std::uint32_t kBlock = 256;

template <class F>
__global__ void run_each(std::uint32_t n, F f) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < n) f(k);
}

template <class F>
__global__ void run_upto(const std::uint32_t* count, F f) {
  const std::uint32_t k = blockIdx.x * blockDim.x + threadIdx.x;
  if (k < *count) f(k);
}

template <class T>
struct FillWith {
  T* p;
  T value;
  __device__ void operator()(std::uint32_t k) const { p[k] = value; }
};

// Device memory of n values, owned; contents unspecified after resize.
template <class T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(DeviceArray&& o) noexcept { *this = std::move(o); }
  DeviceArray& operator=(DeviceArray&& o) noexcept {
    std::swap(p_, o.p_);
    std::swap(n_, o.n_);
    return *this;
  }
  ~DeviceArray() { cudaFree(p_); }
  T* data() { return p_; }
  std::size_t size() const { return n_; }
  void resize(std::size_t n) {
    if (n <= n_) return;
    cudaFree(p_);
    p_ = nullptr;
    n_ = 0;
    check(cudaMalloc(&p_, n * sizeof(T)), "out of device memory");
    n_ = n;
  }

 private:
  T* p_ = nullptr;
  std::size_t n_ = 0;
};

class DeviceExecutor {
 public:
  template <class T>
  using Array = DeviceArray<T>;

  explicit DeviceExecutor(bool profile) : profile_(profile) {}
  DeviceExecutor(const DeviceExecutor&) = delete;
  DeviceExecutor& operator=(const DeviceExecutor&) = delete;
  ~DeviceExecutor() {
    for (cudaEvent_t e : spare_) cudaEventDestroy(e);
    for (const Lap& l : laps_) cudaEventDestroy(l.from);
    if (last_) cudaEventDestroy(last_);
  }

  template <class F>
  void for_each(std::uint32_t n, const F& f) {
    if (n == 0) return;
    run_each<<<(n + kBlock - 1) / kBlock, kBlock>>>(n, f);
    check(cudaGetLastError(), "kernel launch");
  }
  template <class F>
  void for_each_upto(std::uint32_t most, const std::uint32_t* count, const F& f) {
    if (most == 0) return;
    run_upto<<<(most + kBlock - 1) / kBlock, kBlock>>>(count, f);
    check(cudaGetLastError(), "kernel launch");
  }
  template <class T>
  void fill(T* p, std::uint32_t n, const T& value) {
    for_each(n, FillWith<T>{p, value});
  }
  void sort_pairs(std::uint64_t* keys, std::uint32_t* values, std::uint32_t n, int bits) {
    if (n < 2) return;
    key_swap_.resize(n);
    value_swap_.resize(n);
    cub::DoubleBuffer<std::uint64_t> k(keys, key_swap_.data());
    cub::DoubleBuffer<std::uint32_t> v(values, value_swap_.data());
    std::size_t bytes = 0;
    check(cub::DeviceRadixSort::SortPairs(nullptr, bytes, k, v, n, 0, bits), "sort");
    temp_.resize(bytes);
    check(cub::DeviceRadixSort::SortPairs(temp_.data(), bytes, k, v, n, 0, bits), "sort");
    if (k.Current() != keys) {
      check(cudaMemcpy(keys, k.Current(), n * sizeof *keys, cudaMemcpyDeviceToDevice), "sort");
      check(cudaMemcpy(values, v.Current(), n * sizeof *values, cudaMemcpyDeviceToDevice), "sort");
    }
  }
  void inclusive_scan(std::uint32_t* p, std::uint32_t n) {
    std::size_t bytes = 0;
    check(cub::DeviceScan::InclusiveSum(nullptr, bytes, p, p, n), "scan");
    temp_.resize(bytes);
    check(cub::DeviceScan::InclusiveSum(temp_.data(), bytes, p, p, n), "scan");
  }
  template <class T>
  T read(const T* p) {
    T value;
    check(cudaMemcpy(&value, p, sizeof value, cudaMemcpyDeviceToHost), "copy to host");
    settle();  // the copy waited for the device: every event recorded so far has happened
    return value;
  }
  // A stage's time by CUDA events: lap() records one after the stage's work on the stream and
  // returns at once; the times are read at the next read(), which waits for the device anyway.
  // So --metrics (which psweep always passes) adds no synchronisation to a sub-step.
  void lap(double& stage) {
    if (!profile_) return;
    const cudaEvent_t e = event();
    check(cudaEventRecord(e), "event");
    laps_.push_back({last_, e, &stage});
    last_ = e;
  }
  // Before the timed loop: the uploads done, and the first event to time from.
  void warm_up() {
    check(cudaDeviceSynchronize(), "warm-up");
    if (!profile_) return;
    last_ = event();
    check(cudaEventRecord(last_), "event");
  }

  World upload(const World& host) {
    const std::size_t n = host.n;
    for (auto* a : {&x_, &y_, &ux_, &uy_, &impulse_}) a->resize(n);
    for (auto* a : {&pairs_, &walls_}) a->resize(n);
    World w = make_world(host.L, host.r, n, x_.data(), y_.data(), ux_.data(), uy_.data(),
                         pairs_.data(), walls_.data(), impulse_.data());
    w.whole_motion = host.whole_motion;
    w.overlaps_collide = host.overlaps_collide;
    copy(w, host, cudaMemcpyHostToDevice);
    return w;
  }
  void download(const World& device, const World& host) {
    copy(host, device, cudaMemcpyDeviceToHost);
  }

 private:
  static void copy(const World& to, const World& from, cudaMemcpyKind kind) {
    const std::size_t n = from.n;
    for (auto [t, f] : {std::pair{to.x, from.x},
                        {to.y, from.y},
                        {to.ux, from.ux},
                        {to.uy, from.uy},
                        {to.wall_impulse, from.wall_impulse}})
      check(cudaMemcpy(t, f, n * sizeof(double), kind), "copy");
    for (auto [t, f] : {std::pair{to.pair_collisions, from.pair_collisions},
                        {to.wall_collisions, from.wall_collisions}})
      check(cudaMemcpy(t, f, n * sizeof(std::uint64_t), kind), "copy");
  }

  struct Lap {
    cudaEvent_t from, to;
    double* stage;
  };
  cudaEvent_t event() {
    if (spare_.empty()) {
      cudaEvent_t e;
      check(cudaEventCreate(&e), "event");
      return e;
    }
    const cudaEvent_t e = spare_.back();
    spare_.pop_back();
    return e;
  }
  // Adds the finished laps' times to their stages; their start events are free again.
  void settle() {
    for (const Lap& l : laps_) {
      float ms = 0;
      check(cudaEventElapsedTime(&ms, l.from, l.to), "event time");
      *l.stage += ms / 1e3;
      spare_.push_back(l.from);
    }
    laps_.clear();
  }

  bool profile_;
  cudaEvent_t last_ = nullptr;  // the latest lap's event: the next lap's start
  std::vector<Lap> laps_;       // recorded, not yet read
  std::vector<cudaEvent_t> spare_;
  DeviceArray<double> x_, y_, ux_, uy_, impulse_;
  DeviceArray<std::uint64_t> pairs_, walls_, key_swap_;
  DeviceArray<std::uint32_t> value_swap_;
  DeviceArray<unsigned char> temp_;
};

}  // namespace

std::string unavailable() {
  // Asked once per process: psim asks before it reads the scene, simulate() again.
  static const std::string why = [] {
    // Every kernel loaded with the context (in the upload, outside wall_s), not at its first
    // launch inside the loop; before the first CUDA call, which fixes the setting. A user's own
    // setting stays.
    setenv("CUDA_MODULE_LOADING", "EAGER", 0);
    int devices = 0;
    const cudaError_t status = cudaGetDeviceCount(&devices);
    if (status != cudaSuccess)
      return std::string("no CUDA device (") + cudaGetErrorString(status) + ")";
    return std::string(devices == 0 ? "no CUDA device" : "");
  }();
  return why;
}

RunReport run(const World& w, const RunOptions&, const PipelineParams& params) {
  // The device memory a run of n particles needs to start (ParallelStep's arrays), per particle:
  // the state; its cell, id, cell end, pieces, best rank, taken mark and accepted collision; and
  // room for 2n candidates, each with its index, sort key, two round lists and the sort's spare key
  // and value. Plus 64 MiB for CUB's temporaries and the runtime.
  constexpr std::size_t kState = 5 * sizeof(double) + 2 * sizeof(std::uint64_t);
  constexpr std::size_t kParticle =
      sizeof(std::uint64_t) + 4 * sizeof(std::uint32_t) + 1 + sizeof(Candidate);
  constexpr std::size_t kCandidate =
      sizeof(Candidate) + 2 * sizeof(std::uint64_t) + 4 * sizeof(std::uint32_t);
  const std::size_t needed = w.n * (kState + kParticle + 2 * kCandidate) + (std::size_t{64} << 20);
  std::size_t free = 0, total = 0;
  check(cudaMemGetInfo(&free, &total), "device memory");
  if (needed > free)
    throw InputError("engine gpu: the device's memory is too small for N = " + std::to_string(w.n) +
                     ": it needs about " + std::to_string(needed >> 20) + " MiB, " +
                     std::to_string(free >> 20) + " MiB of " + std::to_string(total >> 20) +
                     " MiB are free");
  DeviceExecutor exec(params.profile);
  return run_parallel(exec, w, params);
}

}  // namespace particle::detail::gpu
