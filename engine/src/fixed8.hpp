#pragma once
// `%.8f` without printf: the state lines are 4 doubles each and print mode writes N*(S+1) lines,
// so this is the hot loop of every print-mode run.
//
// Exact for every finite |v| < 2^63 (every value a scene can hold in practice; larger ones and
// non-finite values take snprintf itself). The integer part is truncated exactly; the fraction f
// (exact: a - trunc(a) loses nothing) is a 53-bit integer m times 2^-s with s >= 53, so f * 1e8 is
// the exact 128-bit product m * 1e8 (< 2^80) shifted right by s. The bits shifted out decide the
// rounding exactly, ties to even as glibc's printf does in the default rounding mode: no
// floating-point multiplication by 1e8 is ever rounded. About 5 ns per value against about 350 ns
// for fmt's fixed-precision path.
#include <bit>
#include <cstdint>
#include <cstdio>

namespace particle::detail {

__extension__ using uint128 = unsigned __int128;  // GCC and Clang on 64-bit targets

// `%.8f` of a double never exceeds this: 309 integer digits, sign, point, 8 decimals, NUL.
inline constexpr int kMaxFixed8Chars = 320;

// "00".."99": two digits per table look-up halve the divisions.
inline constexpr char kDigitPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

inline void write_pair(char* out, unsigned v) {
  out[0] = kDigitPairs[2 * v];
  out[1] = kDigitPairs[2 * v + 1];
}

// Decimal digits of v (no sign, no leading zeros); returns the end.
inline char* write_decimal(char* out, std::uint64_t v) {
  int digits = 1;
  for (std::uint64_t p = 10; digits < 20 && v >= p; p *= 10) ++digits;
  char* end = out + digits;
  char* at = end;
  while (v >= 100) {
    at -= 2;
    write_pair(at, static_cast<unsigned>(v % 100));
    v /= 100;
  }
  if (v >= 10)
    write_pair(at - 2, static_cast<unsigned>(v));
  else
    at[-1] = static_cast<char>('0' + v);
  return end;
}

// Exactly 8 digits of v < 1e8, with leading zeros.
inline char* write_8_digits(char* out, std::uint32_t v) {
  const std::uint32_t hi = v / 10000, lo = v % 10000;
  write_pair(out, hi / 100);
  write_pair(out + 2, hi % 100);
  write_pair(out + 4, lo / 100);
  write_pair(out + 6, lo % 100);
  return out + 8;
}

// printf itself, for what the fast path does not cover.
inline char* format_fixed8_slow(char* out, double v) {
  return out + std::snprintf(out, kMaxFixed8Chars, "%.8f", v);
}

// Writes `%.8f` of v (byte-identical to printf's) at out, at most kMaxFixed8Chars - 1 chars;
// returns the end (no NUL).
inline char* format_fixed8(char* out, double v) {
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(v);
  const double a = std::bit_cast<double>(bits & ~(std::uint64_t{1} << 63));
  if (!(a < 0x1p63)) return format_fixed8_slow(out, v);  // huge, inf or NaN
  *out = '-';
  out += bits >> 63;  // printf keeps the sign of -0.0 and of negatives that round to zero
  std::uint64_t whole = static_cast<std::uint64_t>(a);
  const double fraction = a - static_cast<double>(whole);  // exact, in [0, 1)
  std::uint32_t decimals = 0;
  const std::uint64_t fbits = std::bit_cast<std::uint64_t>(fraction);
  const int biased = static_cast<int>(fbits >> 52);
  const std::uint64_t mantissa =
      (fbits & ((std::uint64_t{1} << 52) - 1)) | (biased ? std::uint64_t{1} << 52 : 0);
  const int shift = biased ? 1075 - biased : 1074;  // fraction = mantissa * 2^-shift
  // mantissa * 1e8 < 2^80: a shift past 80 leaves less than half a unit, which rounds to 0.
  if (mantissa != 0 && shift <= 80) {
    const uint128 product = static_cast<uint128>(mantissa) * 100000000u;
    const auto q = static_cast<std::uint64_t>(product >> shift);
    const uint128 rest = product - (static_cast<uint128>(q) << shift);
    const uint128 half = static_cast<uint128>(1) << (shift - 1);
    decimals = static_cast<std::uint32_t>(q + (rest > half || (rest == half && (q & 1))));
    if (decimals == 100000000u) {  // 0.999999995 and up carry into the integer part
      decimals = 0;
      ++whole;
    }
  }
  out = write_decimal(out, whole);
  *out++ = '.';
  return write_8_digits(out, decimals);
}

}  // namespace particle::detail
