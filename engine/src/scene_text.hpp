#pragma once
// The 2019 text format's lines, fields and numbers, read from one buffer holding the whole
// input: no allocation per line, std::from_chars for numbers. Every problem becomes an
// InputError `SOURCE:LINE: FIELD: problem` that shows the offending text escaped and cut short.
//
// Syntax: a line ends at '\n'; trailing spaces, tabs and '\r' (CRLF files) are ignored, so are
// leading spaces and tabs; fields are separated by runs of spaces or tabs. Anything else,
// including a '\r' inside a line or a byte-order mark, belongs to a field.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <istream>
#include <memory>
#include <string>
#include <string_view>

#include "particle/io.hpp"

namespace particle::detail {

// The whole of `in`, read in large blocks (the 1M-particle scene is 57 MB).
class InputText {
 public:
  explicit InputText(std::istream& in);
  std::string_view view() const { return {data_.get(), size_}; }

 private:
  std::unique_ptr<char[]> data_;  // not zero-filled: every byte kept is read from the stream
  std::size_t size_ = 0;
};

using particle::quoted;  // particle/io.hpp

class LineReader {
 public:
  static constexpr int kMaxFields = 8;  // more are counted, not kept

  LineReader(std::string_view text, std::string source) : text_(text), source_(std::move(source)) {}

  // Splits the next line into fields; false at the end of the text.
  bool next() {
    if (pos_ >= text_.size()) return false;
    const char* begin = text_.data() + pos_;
    const char* end = static_cast<const char*>(std::memchr(begin, '\n', text_.size() - pos_));
    if (!end) end = text_.data() + text_.size();
    pos_ = static_cast<std::size_t>(end - text_.data()) + 1;
    ++number_;
    while (end > begin && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r')) --end;
    count_ = 0;
    for (const char* at = begin; at < end;) {
      while (*at == ' ' || *at == '\t') ++at;  // the line ends in a non-blank
      const char* start = at;
      while (at < end && *at != ' ' && *at != '\t') ++at;
      if (count_ < kMaxFields) fields_[count_] = {start, static_cast<std::size_t>(at - start)};
      ++count_;
    }
    return true;
  }

  int count() const { return count_; }
  std::string_view field(int k) const { return fields_[k]; }
  std::int64_t line() const { return number_; }
  const std::string& source() const { return source_; }

  [[noreturn]] void fail(std::string_view field, const std::string& problem) const;
  // For what is missing: names the line after the last one.
  [[noreturn]] void fail_at_end(std::string_view field, const std::string& problem) const;

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::string source_;
  std::int64_t number_ = 0;
  int count_ = 0;
  std::string_view fields_[kMaxFields];
};

// The messages for bad numbers, off the hot path.
[[noreturn]] void bad_integer(const LineReader& r, std::string_view field, std::string_view token);
[[noreturn]] void bad_real(const LineReader& r, std::string_view field, std::string_view token);

// from_chars takes no '+': skip one that a digit or a point follows ("+-1" stays an error).
inline const char* after_plus(std::string_view token) {
  const char* at = token.data();
  return token.size() > 1 && at[0] == '+' && at[1] != '-' ? at + 1 : at;
}

// A field that must be a whole number: digits with an optional sign.
inline std::int64_t parse_integer(const LineReader& r, std::string_view field,
                                  std::string_view token) {
  std::int64_t value = 0;
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  if (ec != std::errc() || stop != end) bad_integer(r, field, token);
  return value;
}

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
  if (at < end && *at == '.')
    for (++at; at < end && static_cast<unsigned>(*at - '0') < 10; ++at, ++digits, ++decimals)
      m = 10 * m + (*at - '0');
  if (at != end || digits == 0 || digits > 19 || m > (std::uint64_t{1} << 53) || decimals > 22)
    return false;
  value = static_cast<double>(m) / kPowers[decimals];
  if (negative) value = -value;
  return true;
}

// A field that must be a finite decimal number: optional sign, digits with an optional point,
// optional exponent. Underflow and overflow are named as such.
inline double parse_real(const LineReader& r, std::string_view field, std::string_view token) {
  double value = 0;
  if (parse_plain_decimal(token, value)) return value;
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  if (ec != std::errc() || stop != end || !std::isfinite(value)) bad_real(r, field, token);
  return value;
}

}  // namespace particle::detail
