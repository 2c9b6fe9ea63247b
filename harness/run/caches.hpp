// The caches of CPU 0 as the kernel describes them (/sys/devices/system/cpu/cpu0/cache/index*):
// what the ceilings' pair kernel must fit into and their bandwidth's arrays must exceed, and the
// caches cachegrind simulates for simulated counters (run/simulated.hpp). A VM reports what its
// hypervisor passes on, which may be the host's whole L3.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace psweep {

struct Cache {
  int level = 0;
  std::string type;  // Data, Instruction, Unified
  std::uint64_t size_bytes = 0;
  int line_bytes = 0;
  int ways = 0;                 // 0 where sysfs does not say
  std::string shared_cpu_list;  // the CPUs that share it, as sysfs lists them ("0-1")
};

// In sysfs's order (index0, index1, ...); empty where sysfs has none.
std::vector<Cache> read_caches(const std::string& root = "/sys/devices/system/cpu/cpu0/cache");

// "48K", "2048K", "480M", "12345" as bytes; 0 for anything else.
std::uint64_t parse_size(const std::string& text);

// The largest data-holding cache (Data or Unified) of the given level, 0 if none; level 0: the
// last level.
std::uint64_t data_cache_bytes(const std::vector<Cache>& caches, int level);

}  // namespace psweep
