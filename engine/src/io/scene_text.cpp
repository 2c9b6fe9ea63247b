// Reading the input line by line, and the messages for what is wrong in it (see io/scene_text.hpp).
#include "io/scene_text.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ios>
#include <limits>

#include "particle/io.hpp"

namespace particle::detail {

namespace {
// Large blocks for speed; more than a line, so a line always fits once the rest is moved out.
constexpr std::size_t kBufferBytes = std::size_t{1} << 20;
static_assert(kBufferBytes > kMaxLineBytes);
}  // namespace

LineReader::LineReader(std::istream& in, std::string source)
    : in_(in.rdbuf()), buffer_(new char[kBufferBytes + kSlack]), source_(std::move(source)) {}

void LineReader::fill() {
  std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
  offset_ += begin_;
  end_ -= begin_;
  begin_ = 0;
  // sgetn returns less than asked only at the end of the stream (it waits on a pipe).
  const auto wanted = static_cast<std::streamsize>(kBufferBytes - end_);
  std::streamsize got = 0;
  try {
    got = in_ ? in_->sgetn(buffer_.get() + end_, wanted) : 0;
  } catch (const std::ios_base::failure&) {
    // libstdc++'s filebuf throws where the read itself fails: the input is a directory, or a
    // device that errs. A message about the input, not an internal error.
    throw InputError(fmt::format("{}: cannot read: {}", source_, std::strerror(errno)));
  }
  end_ += static_cast<std::size_t>(got);
  at_end_ = got < wanted;
}

std::string_view LineReader::whole_lines() {
  if (!at_end_ && end_ - begin_ < kBufferBytes / 2) fill();
  const char* begin = buffer_.get() + begin_;
  const auto* last = static_cast<const char*>(memrchr(begin, '\n', end_ - begin_));
  if (!last || offset_ + static_cast<std::size_t>(last + 1 - buffer_.get()) > limit_) return {};
  return {begin, static_cast<std::size_t>(last + 1 - begin)};
}

void LineReader::limit_lines(std::int64_t lines) {
  limit_ = static_cast<std::uint64_t>(lines) * kMaxLineBytes;
}

void LineReader::too_long(std::int64_t line) const {
  throw InputError(fmt::format(
      "{}:{}: line: longer than {} bytes, its line end included: the most a line of the 2019 "
      "format may hold (is this a scene or an output of that format?)",
      source_, line, kMaxLineBytes));
}

void LineReader::too_much() const {
  throw InputError(fmt::format(
      "{}:{}: input: goes on beyond {} bytes, the most the header allows ({} lines of at most {} "
      "bytes: the 5 header lines and N particle lines)",
      source_, number_, limit_, limit_ / kMaxLineBytes, kMaxLineBytes));
}

namespace {

// The code point of the UTF-8 sequence starting `text` and its length, or length 0 where the
// bytes are not valid UTF-8 (then each is shown as \xNN).
struct CodePoint {
  std::uint32_t code = 0;
  std::size_t length = 0;
};

CodePoint decode_utf8(std::string_view text) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(0);
  const std::size_t length = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC0 ? 2 : 0;
  if (length == 0 || length > text.size() || lead > 0xF4) return {};
  std::uint32_t code = lead & (0x7F >> length);
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(k) & 0xC0) != 0x80) return {};
    code = (code << 6) | (byte(k) & 0x3F);
  }
  constexpr std::uint32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
  if (code < kSmallest[length] || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return {};
  return {code, length};
}

constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

// What a reader cannot guess from the escaped token alone.
std::string hint(std::string_view token) {
  if (token.starts_with(kByteOrderMark))
    return " (the input starts with a UTF-8 byte-order mark, \\uFEFF: save it without one)";
  return "";
}

}  // namespace
}  // namespace particle::detail

namespace particle {

std::string quoted(std::string_view token) {
  std::string out = "\"";
  std::size_t at = 0;
  for (std::size_t shown = 0; at < token.size() && shown < kShownChars; ++shown) {
    const auto c = static_cast<unsigned char>(token[at]);
    std::size_t length = 1;
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
    } else if (const detail::CodePoint p =
                   c >= 0x80 ? detail::decode_utf8(token.substr(at)) : detail::CodePoint{};
               p.length > 0) {
      out += p.code > 0xFFFF ? fmt::format("\\U{:08X}", p.code) : fmt::format("\\u{:04X}", p.code);
      length = p.length;
    } else {
      out += fmt::format("\\x{:02X}", c);
    }
    at += length;
  }
  out += '"';
  if (at < token.size()) out += fmt::format("... ({} bytes)", token.size());
  return out;
}

}  // namespace particle

namespace particle::detail {

void LineReader::fail(std::string_view field, const std::string& problem) const {
  throw InputError(fmt::format("{}:{}: {}: {}", source_, number_, field, problem));
}

void LineReader::fail_at_end(std::string_view field, const std::string& problem) const {
  throw InputError(fmt::format("{}:{}: {}: {}", source_, number_ + 1, field, problem));
}

void bad_integer(const LineReader& r, std::string_view field, std::string_view token) {
  std::int64_t value = 0;
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  if (ec == std::errc::result_out_of_range && stop == end)
    r.fail(field, "integer out of range (beyond 64 bits): " + quoted(token));
  r.fail(field, "expected an integer, got " + quoted(token) + hint(token));
}

void bad_real(const LineReader& r, std::string_view field, std::string_view token) {
  double value = 0;
  const char* end = token.data() + token.size();
  const auto [stop, ec] = std::from_chars(after_plus(token), end, value);
  if (ec == std::errc::result_out_of_range && stop == end) {
    // from_chars leaves the value alone on a range error; strtod tells which side it is on.
    const std::string copy(after_plus(token), end);
    const double nearest = std::strtod(copy.c_str(), nullptr);
    if (std::fabs(nearest) > 1)
      r.fail(field, quoted(token) + " overflows: its magnitude is beyond the largest double, " +
                        fmt::format("{:.3g}", std::numeric_limits<double>::max()));
    r.fail(field, quoted(token) +
                      " underflows: it is not zero but its magnitude is below the smallest "
                      "positive double, " +
                      fmt::format("{:.3g}", std::numeric_limits<double>::denorm_min()));
  }
  if (ec == std::errc() && stop == end)
    r.fail(field, "expected a finite number, got " + quoted(token));
  r.fail(field, "expected a number, got " + quoted(token) + hint(token));
}

}  // namespace particle::detail
