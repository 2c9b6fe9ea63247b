// format_fixed8 against printf's `%.8f`, byte for byte: exact ties, carries, signed zeros, the
// 2^63 edge of the fast path, the fallback, and random values over every magnitude.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/fixed8.hpp"

namespace particle::detail {
namespace {

std::string printf_fixed8(double v) {
  char text[kMaxFixed8Chars];
  std::snprintf(text, sizeof text, "%.8f", v);
  return text;
}

std::string fast_fixed8(double v) {
  char text[kMaxFixed8Chars];
  return std::string(text, format_fixed8(text, v));
}

// Checks v and -v; returns the number of mismatches (each reported once).
int mismatches(double v) {
  int bad = 0;
  for (double s : {v, -v}) {
    const std::string expected = printf_fixed8(s), actual = fast_fixed8(s);
    if (expected != actual) {
      if (++bad == 1)
        ADD_FAILURE() << "%.8f of " << std::hexfloat << s << ": printf " << expected
                      << ", format_fixed8 " << actual;
    }
  }
  return bad;
}

TEST(Fixed8, SignedZerosAndTinyNegatives) {
  EXPECT_EQ(fast_fixed8(0.0), "0.00000000");
  EXPECT_EQ(fast_fixed8(-0.0), "-0.00000000");
  EXPECT_EQ(fast_fixed8(-1e-10), "-0.00000000");
  for (double v : {0.0, 1e-10, 4.9e-9, 5e-9, 5.1e-9, 1e-300, 5e-324, 2.2250738585072014e-308,
                   std::nextafter(5e-9, 0.0), std::nextafter(5e-9, 1.0)})
    EXPECT_EQ(mismatches(v), 0);
}

// v * 1e8 = j * 195312.5 for v = j / 2^9: every odd j is an exact tie, which printf breaks to
// the even digit. Finer binary fractions (2^-10 .. 2^-12) land just beside the tie.
TEST(Fixed8, ExactTiesGoToEvenAndNearTiesRoundCorrectly) {
  EXPECT_EQ(fast_fixed8(1.0 / 512), "0.00195312");
  EXPECT_EQ(fast_fixed8(3.0 / 512), "0.00585938");
  int bad = 0;
  for (double whole : {0.0, 1.0, 7.0, 12345.0, 1e6, 1e9, 4503599627370495.0 / 512})
    for (int k = 9; k <= 12; ++k)
      for (int j = 1; j < 4096; j += 2) bad += mismatches(std::floor(whole) + std::ldexp(j, -k));
  EXPECT_EQ(bad, 0);
}

TEST(Fixed8, CarriesIntoTheIntegerPart) {
  EXPECT_EQ(fast_fixed8(0.999999996), "1.00000000");
  EXPECT_EQ(fast_fixed8(-9.999999999), "-10.00000000");
  EXPECT_EQ(fast_fixed8(99999.999999996), "100000.00000000");
  for (double v : {0.999999995, 0.9999999949999999, 9.999999995, 999999.999999995, 1e15 - 0.5})
    EXPECT_EQ(mismatches(v), 0);
}

// The FMA path's edge (kFmaLimit, about 4.5e7, where a * 1e8 reaches 2^52): values on both
// sides, exact ties and their neighbours just below it, where a * 1e8 keeps the fewest fraction
// bits.
TEST(Fixed8, TheEdgeOfTheFmaPath) {
  int bad = 0;
  for (double v = kFmaLimit * (1 - 1e-7); v < kFmaLimit * (1 + 1e-7);
       v = std::nextafter(v + kFmaLimit * 1e-12, 1e300))
    bad += mismatches(v);
  for (double whole : {std::floor(kFmaLimit) - 1, std::floor(kFmaLimit), 33554431.0})
    for (int j = 1; j < 512; j += 2) {
      const double tie = whole + std::ldexp(j, -9);
      bad += mismatches(tie) + mismatches(std::nextafter(tie, 0.0)) +
             mismatches(std::nextafter(tie, 1e300));
    }
  EXPECT_EQ(bad, 0);
}

TEST(Fixed8, LargeValuesAndTheFallback) {
  const double fast_limit = 0x1p63;
  for (double v :
       {1e15, 1e15 + 0.5, 1e15 + 0.125, std::nextafter(1e15, 0.0), 0x1p52 + 0.5, 0x1p53, 0x1p53 + 2,
        1e17, std::nextafter(fast_limit, 0.0), fast_limit, 1e19, 0x1p64, 1e20, 1e300,
        std::numeric_limits<double>::max(), std::numeric_limits<double>::infinity()})
    EXPECT_EQ(mismatches(v), 0) << v;
  EXPECT_EQ(fast_fixed8(std::numeric_limits<double>::quiet_NaN()),
            printf_fixed8(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(fast_fixed8(-std::numeric_limits<double>::quiet_NaN()),
            printf_fixed8(-std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(fast_fixed8(std::nextafter(fast_limit, 0.0)), "9223372036854774784.00000000");
}

// Random values: coordinates and velocities of ordinary scenes, every binary exponent that the
// fast path covers and some beyond, and raw bit patterns (mostly huge or tiny: the fallback).
TEST(Fixed8, RandomValuesMatchPrintf) {
  std::mt19937_64 rng(20191);
  std::uniform_real_distribution<double> box(0, 20000), speed(-100, 100), unit(0.5, 1);
  std::uniform_int_distribution<int> exponent(-40, 70);
  int bad = 0;
  for (int k = 0; k < 50000; ++k) {
    bad += mismatches(box(rng));
    bad += mismatches(speed(rng));
    bad += mismatches(std::ldexp(unit(rng), exponent(rng)));
    if (k % 16 == 0) bad += mismatches(std::bit_cast<double>(rng()));  // printf is slow on these
    if (bad > 10) break;
  }
  EXPECT_EQ(bad, 0);
}

// Four values at once (a state line's doubles) against printf: the same values as above, ties
// and their neighbours, signed zeros, and the FMA edge, in every position of the four.
TEST(Fixed8, FourAtOnceMatchPrintf) {
  std::mt19937_64 rng(2019);
  std::uniform_real_distribution<double> box(0, 20000), speed(-100, 100), unit(0.5, 1);
  std::uniform_int_distribution<int> exponent(-40, 25);  // 2^26 may pass kFmaLimit
  const double edges[] = {0.0, -0.0, -1e-10, 5e-9, -5e-9, 0.999999995, 9.999999995, 1.0 / 512,
                          3.0 / 512, 12345 + 3.0 / 512, std::nextafter(kFmaLimit, 0.0),
                          -std::nextafter(kFmaLimit, 0.0), 33554431 + 511.0 / 512, 1e-300};
  int bad = 0, fast = 0;
  for (int k = 0; k < 200000 && bad < 10; ++k) {
    double v[4];
    for (double& each : v) {
      switch (rng() % 4) {
        case 0: each = box(rng); break;
        case 1: each = speed(rng); break;
        case 2: each = std::ldexp(unit(rng), exponent(rng)) * (rng() % 2 ? 1 : -1); break;
        default: each = edges[rng() % std::size(edges)];
      }
    }
    char text[4 * kMaxFixed8Chars + 8];
    char* end = text;
    if (!format_four_fixed8(end, v[0], v[1], v[2], v[3])) continue;
    ++fast;
    char expected[4 * kMaxFixed8Chars + 8];
    std::snprintf(expected, sizeof expected, " %.8f %.8f %.8f %.8f", v[0], v[1], v[2], v[3]);
    if (std::string(text, end) != expected && ++bad == 1)
      ADD_FAILURE() << "printf \"" << expected << "\", format_four_fixed8 \""
                    << std::string(text, end) << '"';
  }
  EXPECT_EQ(bad, 0);
#if defined(__AVX2__) && defined(__FMA__)
  EXPECT_EQ(fast, 200000);  // every value above is below kFmaLimit
  char text[4 * kMaxFixed8Chars + 8];
  char* end = text;
  EXPECT_FALSE(format_four_fixed8(end, 1, 2, kFmaLimit, 3));  // the scalar path's
  EXPECT_EQ(end, text);
#endif
}

}  // namespace
}  // namespace particle::detail
