// The caches of CPU 0 from a sysfs tree (run/caches.hpp): what the ceilings size their kernels by
// and cachegrind simulates.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "../scratch_folder.hpp"
#include "run/caches.hpp"

using namespace psweep;

namespace {

TEST(Caches, ReadFromSysfs) {
  const auto root = test_support::scratch_folder("ceilings_caches");
  auto cache = [&](int index, const char* level, const char* type, const char* size) {
    const auto dir = root / ("index" + std::to_string(index));
    std::filesystem::create_directories(dir);
    for (auto [file, text] : {std::pair{"level", level},
                              {"ways_of_associativity", "12"},
                              {"type", type},
                              {"size", size},
                              {"coherency_line_size", "64"},
                              {"shared_cpu_list", "0-1"}})
      std::ofstream(dir / file) << text << "\n";
  };
  cache(0, "1", "Data", "48K");
  cache(1, "1", "Instruction", "64K");
  cache(2, "2", "Unified", "2048K");
  cache(3, "3", "Unified", "480M");
  const std::vector<Cache> caches = read_caches(root.string());
  ASSERT_EQ(caches.size(), 4u);
  EXPECT_EQ(caches[1].type, "Instruction");
  EXPECT_EQ(caches[3].shared_cpu_list, "0-1");
  EXPECT_EQ(caches[3].ways, 12);
  EXPECT_EQ(data_cache_bytes(caches, 1), 48u << 10);  // the instruction cache is not data's
  EXPECT_EQ(data_cache_bytes(caches, 2), 2048u << 10);
  EXPECT_EQ(data_cache_bytes(caches, 0), 480u << 20);
  EXPECT_TRUE(read_caches((root / "none").string()).empty());
  EXPECT_EQ(parse_size("12"), 12u);
  EXPECT_EQ(parse_size("1G"), 1u << 30);
  EXPECT_EQ(parse_size("48KiB"), 0u);
  EXPECT_EQ(parse_size(""), 0u);
}

}  // namespace
