// The ceilings' kernels checked for what they compute (docs/performance.md, "The machine's
// ceilings"): the pair kernel tests every pair of its scene once and finds no candidate, the
// bandwidth's kernels write what they say and count their bytes as STREAM does (the caches'
// reader is psweep's: tests/harness/test_caches.cpp). Their speed is checked against psim and
// memcpy in tests/python/test_ceilings.py.
#include <gtest/gtest.h>


#include "bandwidth.hpp"
#include "pair_kernel.hpp"
#include "spread.hpp"

namespace {

using namespace ceilings;

TEST(PairKernel, TestsEveryPairOnceAndFindsNoCandidate) {
  for (std::uint32_t n : {64u, 100u, 768u}) {
    const KernelScene scene(n);
    const KernelCount count = all_pairs(scene, 3);
    EXPECT_EQ(count.pair_tests, 3ull * n * (n - 1) / 2) << n;
    EXPECT_EQ(count.candidates, 0u) << n;
  }
}

TEST(PairKernel, EveryThreadRunsItsOwnPasses) {
  const KernelTiming one = time_kernel(100, 2, 1);
  const KernelTiming two = time_kernel(100, 2, 2);
  EXPECT_EQ(one.count.pair_tests, 2ull * 100 * 99 / 2);
  EXPECT_EQ(two.count.pair_tests, 2 * one.count.pair_tests);
  EXPECT_GT(one.seconds, 0);
}

TEST(PairKernel, SceneFillsHalfOfL1) {
  EXPECT_EQ(particles_for_l1(48 << 10), 768u);  // 768 x 4 doubles = 24 KiB
  EXPECT_EQ(particles_for_l1(32 << 10), 512u);
  EXPECT_EQ(particles_for_l1(1 << 10), 64u);
  EXPECT_EQ(particles_for_l1(1 << 20), 1024u);
}

TEST(Bandwidth, TriadAndCopyComputeAndCountTheirBytes) {
  Arrays arrays(1001, 2);
  const Moved t = triad(arrays, 3.0, 2);
  EXPECT_EQ(t.bytes, 24u * 1001);
  for (std::size_t i = 0; i < arrays.elements(); ++i)
    ASSERT_EQ(arrays.a()[i], arrays.b()[i] + 3.0 * arrays.c()[i]) << i;
  const Moved c = copy(arrays, 2);
  EXPECT_EQ(c.bytes, 16u * 1001);
  for (std::size_t i = 0; i < arrays.elements(); ++i) ASSERT_EQ(arrays.a()[i], arrays.b()[i]) << i;
}

TEST(Bandwidth, ArraysExceedTheLastLevelWithinTheMemory) {
  constexpr std::uint64_t MiB = 1 << 20;
  // Elements of 8 bytes in each of three arrays.
  EXPECT_EQ(elements_for(32 * MiB, 64 * 1024 * MiB), 4 * 32 * MiB / 3 / 8);  // 4 x the LLC
  EXPECT_EQ(elements_for(480 * MiB, 64 * 1024 * MiB), 256 * MiB / 8);        // capped
  EXPECT_EQ(elements_for(32 * MiB, 256 * MiB), 256 * MiB / 4 / 3 / 8);       // a quarter of memory
  EXPECT_EQ(elements_for(1 * MiB, 64 * 1024 * MiB), 8 * MiB / 8);            // at least 8 MiB each
}

TEST(Spread, MinMedianMax) {
  const Spread s = spread_of({3, 1, 2, 10});
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.median, 2.5);
  EXPECT_EQ(s.max, 10);
  EXPECT_EQ(s.repetitions, 4);
}

}  // namespace
