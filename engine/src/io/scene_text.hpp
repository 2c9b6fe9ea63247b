#pragma once
// The 2019 text format's lines, fields and numbers, read through one reused buffer: no
// allocation per line, std::from_chars for numbers. Every problem becomes an
// InputError `SOURCE:LINE: FIELD: problem` that shows the offending text escaped and cut short.
//
// Syntax: a line ends at '\n'; trailing spaces, tabs and '\r' (CRLF files) are ignored, so are
// leading spaces and tabs; fields are separated by runs of spaces or tabs. Anything else,
// including a '\r' inside a line or a byte-order mark, belongs to a field.
#ifdef __AVX2__
#include <immintrin.h>
#endif

#include <bit>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <istream>
#include <memory>
#include <string>
#include <string_view>

#include "io/fixed8.hpp"  // uint128
#include "particle/io.hpp"

namespace particle::detail {

using particle::quoted;  // particle/io.hpp

// One line's fields. split() may read kReadAhead bytes from the line's start (split_short): the
// buffer holding the line must allow that.
class LineFields {
 public:
  static constexpr int kMaxFields = 8;  // more are counted, not kept
  static constexpr std::size_t kReadAhead = 128;

  // The fields of the line [begin, end), its '\n' left out.
  void split(const char* begin, const char* end) {
    while (end > begin && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r')) --end;
    count_ = 0;
    if (split_short(begin, end)) return;
    for (const char* at = begin; at < end;) {
      while (*at == ' ' || *at == '\t') ++at;  // the line ends in a non-blank
      const char* start = at;
      while (at < end && *at != ' ' && *at != '\t') ++at;
      if (count_ < kMaxFields) fields_[count_] = {start, static_cast<std::size_t>(at - start)};
      ++count_;
    }
  }

  int count() const { return count_; }
  std::string_view field(int k) const { return fields_[k]; }

 private:
  // Splits a line of at most kReadAhead bytes by a mask of its blanks: a particle line's ten
  // field ends cost the byte loop a mispredicted branch each, about half of reading a
  // 1M-particle scene. 128, not 64: psim's output lines pass 64 bytes from L = 10^4 on (a third of
  // checking a program's output at N = 1000, L = 20000 went to the byte loop). Reads kReadAhead
  // bytes from `begin` (LineReader keeps kSlack bytes after its buffer for it). False (nothing
  // split) for a longer line or without AVX2.
  bool split_short(const char* begin, const char* end) {
#ifdef __AVX2__
    using Bits = uint128;
    const auto length = static_cast<std::size_t>(end - begin);
    if (length > kReadAhead) return false;
    const auto blanks = [](const char* at) {
      const __m256i bytes = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at));
      const __m256i blank = _mm256_or_si256(_mm256_cmpeq_epi8(bytes, _mm256_set1_epi8(' ')),
                                            _mm256_cmpeq_epi8(bytes, _mm256_set1_epi8('\t')));
      return Bits{static_cast<std::uint32_t>(_mm256_movemask_epi8(blank))};
    };
    const Bits inside = length == kReadAhead ? ~Bits{0} : (Bits{1} << length) - 1;
    // Bit k: byte k is a blank or past the end.
    const Bits blank = (blanks(begin) | blanks(begin + 32) << 32 | blanks(begin + 64) << 64 |
                        blanks(begin + 96) << 96) |
                       ~inside;
    const Bits word = ~blank;
    Bits starts = word & (blank << 1 | 1);             // a word byte after a blank or first
    Bits ends = word & (blank >> 1 | Bits{1} << 127);  // a word byte before a blank or last
    const auto lowest = [](Bits bits) {
      const auto low = static_cast<std::uint64_t>(bits);
      return low != 0 ? std::countr_zero(low)
                      : 64 + std::countr_zero(static_cast<std::uint64_t>(bits >> 64));
    };
    for (; starts != 0; starts &= starts - 1, ends &= ends - 1) {
      const int first = lowest(starts), last = lowest(ends);
      if (count_ < kMaxFields)
        fields_[count_] = {begin + first, static_cast<std::size_t>(last - first + 1)};
      ++count_;
    }
    return true;
#else
    (void)begin, (void)end;
    return false;
#endif
  }
  int count_ = 0;
  std::string_view fields_[kMaxFields];
};

// The input line by line, read from the stream in large blocks into one buffer that is reused:
// memory stays that buffer's whatever the input, and a line's fields stay valid until the next
// line is read. The read is bounded (particle/io.hpp): a line longer than kMaxLineBytes fails at
// once, and after limit_lines() so does a line that ends beyond that many lines' worth of bytes,
// so neither /dev/zero nor an endless pipe is read without end.
class LineReader {
 public:
  LineReader(std::istream& in, std::string source);

  // Splits the next line into fields; false at the end of the input.
  bool next() {
    const char* newline;
    while (!(newline = static_cast<const char*>(
                 std::memchr(buffer_.get() + begin_, '\n', end_ - begin_)))) {
      if (at_end_) break;
      if (end_ - begin_ >= kMaxLineBytes) too_long(number_ + 1);
      fill();
    }
    if (!newline && begin_ == end_) return false;
    const char* begin = buffer_.get() + begin_;
    const char* end = newline ? newline : buffer_.get() + end_;
    text_ = {begin, static_cast<std::size_t>(end - begin)};
    ++number_;
    if (end - begin >= static_cast<std::ptrdiff_t>(kMaxLineBytes)) too_long(number_);
    begin_ = static_cast<std::size_t>(end - buffer_.get()) + (newline ? 1 : 0);
    if (offset_ + begin_ > limit_) too_much();
    fields_.split(begin, end);
    return true;
  }

  // The unread input's whole lines, up to and including the last '\n' in the buffer (refilled
  // first when less than half of it is left), for a caller that reads them by itself and then
  // skip()s them; empty when they would go beyond limit_lines(), which next() reports.
  std::string_view whole_lines();
  // Takes the bytes whole_lines() gave as read: `lines` lines.
  void skip(std::string_view block, std::int64_t lines) {
    begin_ += block.size();
    number_ += lines;
  }

  // From here on a line that ends beyond `lines` x kMaxLineBytes bytes of input fails: what the
  // header allows (N + 5 lines of at most kMaxLineBytes).
  void limit_lines(std::int64_t lines);

  const LineFields& fields() const { return fields_; }
  std::string_view text() const { return text_; }  // the line as read, without its '\n'
  int count() const { return fields_.count(); }
  std::string_view field(int k) const { return fields_.field(k); }
  std::int64_t line() const { return number_; }
  const std::string& source() const { return source_; }

  [[noreturn]] void fail(std::string_view field, const std::string& problem) const;
  // For what is missing: names the line after the last one.
  [[noreturn]] void fail_at_end(std::string_view field, const std::string& problem) const;

 private:
  // Moves the unread bytes to the front of the buffer and reads more after them.
  void fill();

  [[noreturn]] void too_long(std::int64_t line) const;
  [[noreturn]] void too_much() const;

  std::streambuf* in_;
  // kBufferBytes and kSlack more, so that split_short may read kReadAhead bytes from any line
  // start. Not zero-filled: every byte used is read from the stream (split_short masks what lies
  // beyond).
  static constexpr std::size_t kSlack = LineFields::kReadAhead;
  std::unique_ptr<char[]> buffer_;
  std::size_t begin_ = 0, end_ = 0;  // the bytes read and not yet split into lines
  bool at_end_ = false;              // the stream has no more
  std::uint64_t offset_ = 0;         // of buffer_[0] in the input
  std::uint64_t limit_ = UINT64_MAX;
  std::string source_;
  std::int64_t number_ = 0;
  std::string_view text_;
  LineFields fields_;
};

// The messages for bad numbers, off the hot path.
[[noreturn]] void bad_integer(const LineReader& r, std::string_view field, std::string_view token);
[[noreturn]] void bad_real(const LineReader& r, std::string_view field, std::string_view token);

// from_chars takes no '+': skip one that a digit or a point follows ("+-1" stays an error).
inline const char* after_plus(std::string_view token) {
  const char* at = token.data();
  return token.size() > 1 && at[0] == '+' && at[1] != '-' ? at + 1 : at;
}

// A whole number: digits with an optional sign. False for anything else.
inline bool try_parse_integer(std::string_view token, std::int64_t& value) {
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  return ec == std::errc() && stop == end;
}

// A field that must be a whole number.
inline std::int64_t parse_integer(const LineReader& r, std::string_view field,
                                  std::string_view token) {
  std::int64_t value = 0;
  if (!try_parse_integer(token, value)) bad_integer(r, field, token);
  return value;
}

// The 8 bytes at `at` as one word, the first byte the lowest (little-endian).
inline std::uint64_t load8(const char* at) {
  std::uint64_t bytes;
  std::memcpy(&bytes, at, 8);
  return bytes;
}

// Whether the 8 bytes of `bytes` are all decimal digits: each byte's high half is 3 and adding 6
// carries none of them past '9'.
inline bool eight_digits(std::uint64_t bytes) {
  return (bytes & 0xF0F0F0F0F0F0F0F0) == 0x3030303030303030 &&
         ((bytes + 0x0606060606060606) & 0xF0F0F0F0F0F0F0F0) == 0x3030303030303030;
}
inline bool eight_digits(const char* at) { return eight_digits(load8(at)); }

// The value of 8 decimal digits, the first (lowest) byte the most significant (little-endian
// SWAR: pairs, then fours, then the eight, by three multiplications).
inline std::uint32_t eight_digits_value(std::uint64_t v) {
  v -= 0x3030303030303030;
  v = (v * 10 + (v >> 8)) & 0x00FF00FF00FF00FF;
  v = (v * 100 + (v >> 16)) & 0x0000FFFF0000FFFF;
  return static_cast<std::uint32_t>(v * 10000 + (v >> 32));
}
inline std::uint32_t eight_digits_value(const char* at) { return eight_digits_value(load8(at)); }

// Clinger's fast path for the common field `[+-]digits[.digits]`: at most 19 digits forming an
// integer m <= 2^53, and at most 22 decimals k. m and 10^k are then exact doubles and one IEEE
// division gives the correctly rounded m / 10^k: the same double as from_chars, in a third of its
// instructions. False for anything else (exponents, more digits), which from_chars reads.
inline bool parse_plain_decimal(std::string_view token, double& value) {
  static constexpr double kPowers[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                       1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const char* at = token.data();
  const char* end = at + token.size();
  const bool negative = at < end && *at == '-';
  at += at < end && (*at == '-' || *at == '+');
  std::uint64_t m = 0;
  int digits = 0, decimals = 0;
  for (; at < end && static_cast<unsigned>(*at - '0') < 10; ++at, ++digits)
    m = 10 * m + (*at - '0');
  if (at < end && *at == '.') {
    // Eight decimals at a time while eight digits remain (psim's own output has exactly eight).
    for (++at; end - at >= 8 && eight_digits(at); at += 8, digits += 8, decimals += 8)
      m = 100000000 * m + eight_digits_value(at);
    for (; at < end && static_cast<unsigned>(*at - '0') < 10; ++at, ++digits, ++decimals)
      m = 10 * m + (*at - '0');
  }
  if (at != end || digits == 0 || digits > 19 || m > (std::uint64_t{1} << 53) || decimals > 22)
    return false;
  value = static_cast<double>(m) / kPowers[decimals];
  if (negative) value = -value;
  return true;
}

// A finite decimal number: optional sign, digits with an optional point, optional exponent.
// False for anything else.
inline bool try_parse_real(std::string_view token, double& value) {
  if (parse_plain_decimal(token, value)) return true;
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  return ec == std::errc() && stop == end && std::isfinite(value);
}

// A field that must be a finite decimal number. Underflow and overflow are named as such.
inline double parse_real(const LineReader& r, std::string_view field, std::string_view token) {
  double value = 0;
  if (!try_parse_real(token, value)) bad_real(r, field, token);
  return value;
}

}  // namespace particle::detail
