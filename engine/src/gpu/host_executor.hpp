#pragma once
// The GPU engine's sub-step run on the host, one index at a time (gpu/parallel_step.hpp's
// executor interface): the same stage functions the device runs, in plain loops over host
// memory, so that `make test` checks the GPU engine's algorithm against `brute` on any machine.
// A radix sort is stable, so sort_pairs is a stable sort by key.
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

#include "gpu/parallel_step.hpp"
#include "step/pipeline.hpp"

namespace particle::detail::gpu {

struct HostExecutor {
  template <class T>
  struct Array {
    std::vector<T> v;
    T* data() { return v.data(); }
    std::size_t size() const { return v.size(); }
    void resize(std::size_t n) { v.resize(n); }
  };

  template <class F>
  void for_each(std::uint32_t n, const F& f) {
    for (std::uint32_t k = 0; k < n; ++k) f(k);
  }
  template <class F>
  void for_each_upto(std::uint32_t, const std::uint32_t* count, const F& f) {
    for_each(*count, f);
  }
  template <class T>
  void fill(T* p, std::uint32_t n, const T& value) {
    std::fill(p, p + n, value);
  }
  void sort_pairs(std::uint64_t* keys, std::uint32_t* values, std::uint32_t n, int bits) {
    const std::uint64_t mask = bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return (keys[a] & mask) < (keys[b] & mask);
    });
    std::vector<std::uint64_t> k(n);
    std::vector<std::uint32_t> v(n);
    for (std::uint32_t m = 0; m < n; ++m) {
      k[m] = keys[order[m]];
      v[m] = values[order[m]];
    }
    std::copy(k.begin(), k.end(), keys);
    std::copy(v.begin(), v.end(), values);
  }
  void inclusive_scan(std::uint32_t* p, std::uint32_t n) { std::partial_sum(p, p + n, p); }
  template <class T>
  T read(const T* p) {
    return *p;
  }
  void lap(double& stage) { watch.lap(stage); }
  World upload(const World& host) { return host; }
  void warm_up() {}
  void download(const World&, const World&) {}

  Stopwatch watch;
};

}  // namespace particle::detail::gpu
