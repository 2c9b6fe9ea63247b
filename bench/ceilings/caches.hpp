#pragma once
// The caches of CPU 0 as the kernel describes them (/sys/devices/system/cpu/cpu0/cache/index*):
// what the pair kernel's scene must fit into and what the bandwidth's arrays must exceed. A VM
// reports what its hypervisor passes on, which may be the host's whole L3.
#include <cstdint>
#include <string>
#include <vector>

namespace ceilings {

struct Cache {
  int level = 0;
  std::string type;  // Data, Instruction, Unified
  std::uint64_t size_bytes = 0;
  int line_bytes = 0;
  std::string shared_cpu_list;  // the CPUs that share it, as sysfs lists them ("0-1")
};

// In sysfs's order (index0, index1, ...); empty where sysfs has none.
std::vector<Cache> read_caches(const std::string& root = "/sys/devices/system/cpu/cpu0/cache");

// "48K", "2048K", "480M", "12345" as bytes; 0 for anything else.
std::uint64_t parse_size(const std::string& text);

// The largest data-holding cache (Data or Unified) of the given level, 0 if none; level 0: the
// last level.
std::uint64_t data_cache_bytes(const std::vector<Cache>& caches, int level);

}  // namespace ceilings
