#pragma once
// `%.8f` without printf: the state lines are 4 doubles each and print mode writes N*(S+1) lines,
// so this is the hot loop of every print-mode run.
//
// Exact for every finite |v| < 2^63 (every value a scene can hold in practice; larger ones and
// non-finite values take snprintf itself). The integer part is truncated exactly; the fraction f
// (exact: a - trunc(a) loses nothing) is a 53-bit integer m times 2^-s with s >= 53, so f * 1e8 is
// the exact 128-bit product m * 1e8 (< 2^80) shifted right by s. The bits shifted out decide the
// rounding exactly, ties to even as glibc's printf does in the default rounding mode. Below
// kFmaLimit (4.5e7: the coordinates and speeds of any ordinary scene), where the target has an
// FMA, a shorter path finds the same integer round(|v| * 1e8) from the rounded product and the
// FMA's exact residual: 8.9 against 13.4 ns per value on the 2-core Xeon (the 128-bit path took
// 5.7x less CPU time per value than fmt's fixed-precision path, 16x less than snprintf).
#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "particle/output_text.hpp"  // kMaxFixed8Chars

namespace particle::detail {

__extension__ using uint128 = unsigned __int128;  // GCC and Clang on 64-bit targets

// `%.8f` of a double never exceeds kMaxFixed8Chars (particle/output_text.hpp): 309 integer
// digits, sign, point, 8 decimals, NUL.

// "00".."99": two digits per table look-up halve the divisions.
inline constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// Decimal digits of any v (no sign, no leading zeros); returns the end.
inline char* write_decimal_long(char* out, std::uint64_t v) {
  int digits = 1;
  for (std::uint64_t p = 10; digits < 20 && v >= p; p *= 10) ++digits;
  char* end = out + digits;
  char* at = end;
  for (; v >= 100; v /= 100) {
    at -= 2;
    std::memcpy(at, kDigitPairs + 2 * (v % 100), 2);
  }
  if (v >= 10)
    std::memcpy(at - 2, kDigitPairs + 2 * v, 2);
  else
    at[-1] = static_cast<char>('0' + v);
  return end;
}

// The 8 decimal digits of v < 1e8 as 8 bytes (values 0-9), the first digit in the lowest byte:
// SWAR, splitting 4+4, then 2+2 in each half, then 1+1, with multiply-shift divisions that are
// exact in these ranges. No table and no branch.
inline std::uint64_t digits8(std::uint32_t v) {
  const std::uint64_t quads = v / 10000 | static_cast<std::uint64_t>(v % 10000) << 32;
  const std::uint64_t hundreds = (quads * 10486 >> 20) & 0x0000007F0000007Full;  // x / 100
  const std::uint64_t pairs = hundreds | (quads - 100 * hundreds) << 16;
  const std::uint64_t tens = (pairs * 103 >> 10) & 0x000F000F000F000Full;  // x / 10
  return tens | (pairs - 10 * tens) << 8;
}

constexpr std::uint64_t kAsciiZeros = 0x3030303030303030ull;

// Exactly 8 digits of v < 1e8, with leading zeros; writes 8 bytes.
inline char* write_8_digits(char* out, std::uint32_t v) {
  const std::uint64_t text = digits8(v) + kAsciiZeros;
  std::memcpy(out, &text, 8);
  return out + 8;
}

// Decimal digits of v (no sign, no leading zeros); returns the end. Below 1e8 it stores 8 bytes
// whatever the length (the caller's buffer has room) and drops the leading zeros by a shift.
inline char* write_decimal(char* out, std::uint64_t v) {
  if (v >= 100000000) return write_decimal_long(out, v);
  const std::uint64_t digits = digits8(static_cast<std::uint32_t>(v));
  // Leading zero digits are the low zero bytes; the last digit always stays.
  const int zeros = std::countr_zero(digits | std::uint64_t{1} << 56) / 8;
  const std::uint64_t text = (digits + kAsciiZeros) >> (8 * zeros);
  std::memcpy(out, &text, 8);
  return out + 8 - zeros;
}

// printf itself, for what the fast path does not cover.
inline char* format_fixed8_slow(char* out, double v) {
  return out + std::snprintf(out, kMaxFixed8Chars, "%.8f", v);
}

// Below this, a * 1e8 rounded to an integer has at most 52 bits: the FMA path below applies.
inline constexpr double kFmaLimit = 0x1p52 / 1e8;  // about 4.5e7

// round(a * 1e8), ties to even, exact for 0 <= a < kFmaLimit. p = a * 1e8 rounded, and the FMA's
// residual e = a * 1e8 - p is exact, so the exact product is p + e. p < 2^52 is a multiple of
// half a unit or finer, so r = nearbyint(p) and d = p - r are exact, and |d| < 1/2 means r is
// the answer (|e| is at most half of p's last place, which d's distance to 1/2 exceeds). Only
// d = +-1/2 is a decision, which e's sign makes: beyond the half a unit more, short of it r,
// exactly on it the even r that nearbyint chose (the default rounding mode, as printf's).
inline std::uint64_t round_times_1e8(double a) {
  const double p = a * 1e8;
  const double e = std::fma(a, 1e8, -p);
  const double r = std::nearbyint(p);
  const double d = p - r;
  const auto q = static_cast<std::uint64_t>(r);
  return q + (d == 0.5 && e > 0) - (d == -0.5 && e < 0);
}

// Writes `%.8f` of v (byte-identical to printf's) at out, at most kMaxFixed8Chars - 1 chars;
// returns the end (no NUL).
inline char* format_fixed8(char* out, double v) {
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(v);
  const double a = std::bit_cast<double>(bits & ~(std::uint64_t{1} << 63));
  if (!(a < 0x1p63)) return format_fixed8_slow(out, v);  // huge, inf or NaN
  *out = '-';
  out += bits >> 63;  // printf keeps the sign of -0.0 and of negatives that round to zero
#ifdef __FMA__        // a hardware FMA (without one std::fma is a slow library call)
  if (a < kFmaLimit) {
    const std::uint64_t q = round_times_1e8(a);
    const auto whole = static_cast<std::uint32_t>(q / 100000000u);  // < 1e8
    out = write_decimal(out, whole);
    *out++ = '.';
    return write_8_digits(out, static_cast<std::uint32_t>(q - 100000000ull * whole));
  }
#endif
  std::uint64_t whole = static_cast<std::uint64_t>(a);
  const double fraction = a - static_cast<double>(whole);  // exact, in [0, 1)
  const std::uint64_t fbits = std::bit_cast<std::uint64_t>(fraction);
  const int biased = static_cast<int>(fbits >> 52);
  const std::uint64_t mantissa =
      (fbits & ((std::uint64_t{1} << 52) - 1)) | (biased ? std::uint64_t{1} << 52 : 0);
  // fraction = mantissa * 2^-shift, shift >= 53. mantissa * 1e8 < 2^80, so a shift of 81 or
  // more rounds to 0 like 81 does.
  const int shift = std::min(biased ? 1075 - biased : 1074, 81);
  const uint128 product = static_cast<uint128>(mantissa) * 100000000u;
  // Round half to even without a branch: add half a unit less one, plus one more when the
  // truncated quotient is odd (then an exact half carries it to the even neighbour).
  const auto odd = static_cast<unsigned>(product >> shift) & 1u;
  const uint128 bias = (static_cast<uint128>(1) << (shift - 1)) - 1 + odd;
  std::uint32_t decimals = static_cast<std::uint32_t>((product + bias) >> shift);
  const bool carry = decimals == 100000000u;  // 0.999999995 and up: into the integer part
  whole += carry;
  decimals -= carry ? 100000000u : 0u;
  out = write_decimal(out, whole);
  *out++ = '.';
  return write_8_digits(out, decimals);
}

// ` v0 v1 v2 v3`: four `%.8f` values, each after a space, written at `out` (which moves to their
// end); false, writing nothing, unless the target has AVX2 and an FMA and every |v| < kFmaLimit.
// A state line's four doubles at once: round_times_1e8 in four lanes, the integer split into
// groups of four digits by exact multiplications (fl(1e-8) and fl(1e-4) exceed 10^-8 and 10^-4,
// so floor(q * fl(1e-8)) never falls short, and for q < 2^52 it never reaches the next integer),
// and all 64 digits converted at once in 16-bit lanes. 26 against 48 ns per line (microbenchmark
// on the 2-core Xeon).
inline bool format_four_fixed8(char*& out, double v0, double v1, double v2, double v3) {
#if defined(__AVX2__) && defined(__FMA__)
  const __m256d v = _mm256_set_pd(v3, v2, v1, v0);
  const __m256d a = _mm256_andnot_pd(_mm256_set1_pd(-0.0), v);
  if (_mm256_movemask_pd(_mm256_cmp_pd(a, _mm256_set1_pd(kFmaLimit), _CMP_LT_OQ)) != 0xF)
    return false;
  const __m256d e8 = _mm256_set1_pd(1e8), zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1);
  const __m256d p = _mm256_mul_pd(a, e8);
  const __m256d e = _mm256_fmsub_pd(a, e8, p);
  const __m256d r = _mm256_round_pd(p, _MM_FROUND_CUR_DIRECTION | _MM_FROUND_NO_EXC);
  const __m256d d = _mm256_sub_pd(p, r);
  const __m256d up = _mm256_and_pd(_mm256_cmp_pd(d, _mm256_set1_pd(0.5), _CMP_EQ_OQ),
                                   _mm256_cmp_pd(e, zero, _CMP_GT_OQ));
  const __m256d down = _mm256_and_pd(_mm256_cmp_pd(d, _mm256_set1_pd(-0.5), _CMP_EQ_OQ),
                                     _mm256_cmp_pd(e, zero, _CMP_LT_OQ));
  const __m256d q =  // round_times_1e8, exact integers below 2^52
      _mm256_sub_pd(_mm256_add_pd(r, _mm256_and_pd(up, one)), _mm256_and_pd(down, one));
  const __m256d whole = _mm256_floor_pd(_mm256_mul_pd(q, _mm256_set1_pd(1e-8)));
  const __m256d decimals = _mm256_sub_pd(q, _mm256_mul_pd(whole, e8));
  // The four-digit groups: high and low of each part, every product and difference exact.
  const auto groups = [](__m256d part) {
    const __m256d high = _mm256_floor_pd(_mm256_mul_pd(part, _mm256_set1_pd(1e-4)));
    const __m256d low = _mm256_sub_pd(part, _mm256_mul_pd(high, _mm256_set1_pd(1e4)));
    return _mm_or_si128(_mm256_cvttpd_epi32(high), _mm_slli_epi32(_mm256_cvttpd_epi32(low), 16));
  };
  // 16-bit lanes [high0 low0 ... high3 low3] of the integer parts, then of the decimals.
  const __m256i x = _mm256_set_m128i(groups(decimals), groups(whole));
  const __m256i hundreds = _mm256_srli_epi16(_mm256_mulhi_epu16(x, _mm256_set1_epi16(5243)), 3);
  const __m256i rest = _mm256_sub_epi16(x, _mm256_mullo_epi16(hundreds, _mm256_set1_epi16(100)));
  // y < 100 -> the bytes tens, ones: y * 256 - tens * (10 * 256 - 1).
  const auto two_digits = [](__m256i y) {
    const __m256i tens = _mm256_srli_epi16(_mm256_mullo_epi16(y, _mm256_set1_epi16(103)), 10);
    return _mm256_sub_epi16(_mm256_slli_epi16(y, 8),
                            _mm256_mullo_epi16(tens, _mm256_set1_epi16(2559)));
  };
  const __m256i high = two_digits(hundreds), low = two_digits(rest);
  const __m256i zeros = _mm256_set1_epi8('0');
  // 8 digits per 64-bit lane: integer parts 0 1 4 5 and decimals 2 3 6 7 of values 0 1 2 3.
  alignas(32) std::uint64_t text[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(text),
                     _mm256_add_epi8(_mm256_unpacklo_epi16(high, low), zeros));
  _mm256_store_si256(reinterpret_cast<__m256i*>(text + 4),
                     _mm256_add_epi8(_mm256_unpackhi_epi16(high, low), zeros));
  static constexpr int kWhole[4] = {0, 1, 4, 5}, kDecimals[4] = {2, 3, 6, 7};
  const int signs = _mm256_movemask_pd(v);  // printf keeps the sign of -0.0 and of tiny negatives
  char* at = out;
  for (int k = 0; k < 4; ++k) {
    at[0] = ' ';
    at[1] = '-';
    at += 1 + ((signs >> k) & 1);
    const std::uint64_t digits = text[kWhole[k]];
    // Leading zeros of the integer part go; its last digit stays.
    const int skip = std::countr_zero((digits - kAsciiZeros) | std::uint64_t{1} << 56) / 8;
    const std::uint64_t kept = digits >> (8 * skip);
    std::memcpy(at, &kept, 8);
    at += 8 - skip;
    *at = '.';
    std::memcpy(at + 1, &text[kDecimals[k]], 8);
    at += 9;
  }
  out = at;
  return true;
#else
  (void)out, (void)v0, (void)v1, (void)v2, (void)v3;
  return false;
#endif
}

}  // namespace particle::detail
