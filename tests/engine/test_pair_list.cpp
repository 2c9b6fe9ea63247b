// The cells engine's pair list (broad_phase/pair_list.hpp) against every pair of the scene: read
// back through its own search, with a contact distance far beyond the list's bound and no
// velocities, every listed pair is a receding overlap, named once.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "broad_phase/pair_list.hpp"
#include "parallel/team.hpp"
#include "step/float_pretest.hpp"
#include "world_fixture.hpp"

namespace particle::detail {
namespace {

// Every pair within the bound (a cell's side) on both axes, once, built by 1 and 3 threads: at
// 0.3 and 1 particle a cell a particle's two spans fit in one group of eight (the row above's
// positions expanded after the own row's), at 6 a cell they do not (a group per span, and more).
TEST(PairList, ListsEveryPairWithinItsBoundOnce) {
  constexpr int kSide = 40;
  constexpr double kL = 160, kCell = kL / kSide;
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> position(0, kL);
  for (const double per_cell : {0.3, 1.0, 6.0}) {
    const auto n = static_cast<std::size_t>(per_cell * kSide * kSide);
    std::vector<testing::Body> bodies;
    for (std::size_t i = 0; i < n; ++i) bodies.push_back({position(rng), position(rng), 0, 0});
    testing::WorldFixture f(kL, 4 * kCell, bodies);  // contact at 8 cells: every listed pair
    std::set<std::pair<std::uint32_t, std::uint32_t>> want;
    for (std::uint32_t i = 0; i < n; ++i)
      for (std::uint32_t j = i + 1; j < n; ++j)
        if (std::fabs(f.x[i] - f.x[j]) <= kCell && std::fabs(f.y[i] - f.y[j]) <= kCell)
          want.insert({i, j});
    for (const int threads : {1, 3}) {
      SCOPED_TRACE(::testing::Message() << per_cell << " a cell, T = " << threads);
      CellIndex index;
      PairList list;
      Team team(threads);
#pragma omp parallel num_threads(threads)
      {
        const TeamScope scope(team);
        team_single([&] { index.copy_velocities(false); });
        index.build(
            f.w, [&] { index.set_grid(kSide, kL); },
            [&](std::size_t lo, std::size_t hi, std::uint32_t* cells) {
              for (std::size_t i = lo; i < hi; ++i) cells[i] = index.cell_of(f.w.x[i], f.w.y[i]);
            },
            [] {}, [] {});
        list.build(index, kCell);
      }
      const std::vector<std::uint8_t> apart(n, 0);
      // Searched in double on the World, and (AVX-512 or AVX2) on float records with the float
      // pre-test.
      std::vector<FloatParticle> records;
      for (std::uint32_t i = 0; i < n; ++i)
        records.push_back({static_cast<float>(f.w.x[i]), static_cast<float>(f.w.y[i]), 0, 0});
      const FloatSubStepPretest pretest(f.w.s, kL, 0);
      for (const bool in_float : {false, FloatPretest::applies(f.w.s, kL, 0)}) {
        SCOPED_TRACE(in_float ? "float records" : "World");
        ThreadScratch out;
        for (std::uint32_t piece = 0; piece < list.pieces(); ++piece)
          list.test_piece(piece, f.w, in_float ? records.data() : nullptr,
                          in_float ? &pretest : nullptr, apart.data(), out);
        std::set<std::pair<std::uint32_t, std::uint32_t>> got;
        for (const Candidate& c : out.receding) got.insert({c.i, c.j});
        EXPECT_EQ(got.size(), out.receding.size()) << "a pair listed twice";
        EXPECT_EQ(got, want);
      }
      EXPECT_GT(want.size(), n / 2);
    }
  }
}

#ifdef __AVX2__
// The cells of four particles a register (the cells engine's binning) are cell_of()'s: at the
// walls, on every line between cells and an ulp to either side of it, and anywhere else.
TEST(CellIndex, CellsOfFourAreCellOfs) {
  std::mt19937_64 rng(5);
  for (const int side : {1, 3, 141, 1000, 32768}) {
    SCOPED_TRACE(::testing::Message() << side << " cells a side");
    constexpr double kL = 2000;
    CellIndex index;
    index.set_grid(side, kL);
    std::vector<double> values = {0, kL, std::nextafter(kL, 0.0), 0x1p-1074};
    std::uniform_real_distribution<double> position(0, kL);
    for (int k = 0; k < 4000; ++k) values.push_back(position(rng));
    for (int line = 1; line < std::min(side, 2000); ++line) {
      const double at = kL / side * line;
      values.insert(values.end(), {at, std::nextafter(at, 0.0), std::nextafter(at, kL)});
    }
    while (values.size() % 4 != 0) values.push_back(kL);
    std::uniform_int_distribution<std::size_t> pick(0, values.size() - 1);
    int mismatches = 0;
    for (std::size_t k = 0; k < values.size(); k += 4) {
      alignas(32) double x[4], y[4];
      for (int l = 0; l < 4; ++l) {
        x[l] = values[k + static_cast<std::size_t>(l)];
        y[l] = values[pick(rng)];
      }
      alignas(16) std::uint32_t cells[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(cells),
                      index.cells_of(_mm256_load_pd(x), _mm256_load_pd(y)));
      for (int l = 0; l < 4; ++l) mismatches += cells[l] != index.cell_of(x[l], y[l]);
    }
    EXPECT_EQ(mismatches, 0);
  }
}
#endif

}  // namespace
}  // namespace particle::detail
