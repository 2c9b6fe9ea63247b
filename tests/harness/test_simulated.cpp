// Simulated counters (run/simulated.hpp): cachegrind's summary read into the three counters,
// its options sized from a sysfs tree, a run's counters filled only where the hardware left
// them empty, and the config key that asks for them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "../scratch_folder.hpp"
#include "config/config.hpp"
#include "run/simulated.hpp"

using namespace psweep;

namespace {

TEST(Simulated, ReadsCachegrindsSummary) {
  // cachegrind 3.19 with --cache-sim=yes --branch-sim=yes (numbers made up)
  const std::string text =
      "desc: I1 cache:         65536 B, 64 B, 16-way associative\n"
      "cmd: psim --engine brute scene.in\n"
      "events: Ir I1mr ILmr Dr D1mr DLmr Dw D1mw DLmw Bc Bcm Bi Bim\n"
      "fl=???\nfn=main\n0 1 2 3 4 5 6 7 8 9 10 11 12 13\n"
      "summary: 1000 1 2 300 3 4 200 5 6 400 7 8 9\n";
  const auto counts = parse_cachegrind(text);
  ASSERT_TRUE(counts);
  EXPECT_EQ(counts->instructions, 1000u);
  EXPECT_EQ(counts->ll_misses, 2u + 4u + 6u);  // ILmr + DLmr + DLmw
  EXPECT_EQ(counts->branch_misses, 7u + 9u);   // Bcm + Bim
  // make regress's counts (--cache-sim=no) hold instructions only: nothing to fill misses with
  EXPECT_FALSE(parse_cachegrind("events: Ir\nsummary: 1000\n"));
  EXPECT_FALSE(parse_cachegrind("events: Ir ILmr\n"));
}

TEST(Simulated, CachesSizedFromSysfsWithPowerOfTwoSets) {
  const auto root = test_support::scratch_folder("simulated-caches");
  auto cache = [&](int index, const char* level, const char* type, const char* size,
                   const char* ways) {
    const auto dir = root / ("index" + std::to_string(index));
    std::filesystem::create_directories(dir);
    for (auto [file, text] : {std::pair{"level", level},
                              {"type", type},
                              {"size", size},
                              {"coherency_line_size", "64"},
                              {"ways_of_associativity", ways}})
      std::ofstream(dir / file) << text << "\n";
  };
  cache(0, "1", "Data", "48K", "12");
  cache(1, "1", "Instruction", "64K", "16");
  cache(2, "2", "Unified", "2048K", "16");
  cache(3, "3", "Unified", "480M", "16");  // 491520 sets: down to 262144
  EXPECT_EQ(cachegrind_options(root.string()),
            "--cache-sim=yes --branch-sim=yes --D1=49152,12,64 --I1=65536,16,64 "
            "--LL=268435456,16,64");
  EXPECT_EQ(cachegrind_options((root / "none").string()), "--cache-sim=yes --branch-sim=yes");
}

TEST(Simulated, FillsOnlyWhatTheHardwareLeftEmpty) {
  const SimulatedCounts simulated{1000, 12, 16};
  EventCounts hardware;
  hardware.instructions = 990;
  hardware.branch_misses = 20;
  EXPECT_EQ(fill_counters(hardware, &simulated), "hardware");
  EXPECT_EQ(hardware.instructions, 990u);  // untouched
  EXPECT_EQ(hardware.branch_misses, 20u);
  EXPECT_FALSE(hardware.cache_misses);

  EventCounts none;
  EXPECT_EQ(fill_counters(none, &simulated), "simulated");
  EXPECT_EQ(none.instructions, 1000u);
  EXPECT_EQ(none.cache_misses, 12u);
  EXPECT_EQ(none.branch_misses, 16u);

  EventCounts neither;
  EXPECT_EQ(fill_counters(neither, nullptr), "");
  EXPECT_FALSE(neither.instructions);
}

TEST(Simulated, ConfigKey) {
  const std::string base = R"("base": {"engine": "brute", "N": 10, "L": 100, "r": 1, "S": 1})";
  EXPECT_FALSE(parse_config("{" + base + "}", "c.json").simulate_counters);
  EXPECT_TRUE(
      parse_config("{" + base + R"(, "counters": "simulate"})", "c.json").simulate_counters);
  try {
    parse_config("{" + base + R"(, "counters": "cachegrind"})", "c.json");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("counters"), std::string::npos) << e.what();
  }
}

}  // namespace
