#include "output_format.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <array>
#include <cerrno>
#include <charconv>
#include <cstring>

#include "particle/io.hpp"

namespace particle::check {

namespace {

// Blank lines after the last state line: a trailing newline or two, never an endless stream.
constexpr int kMaxTrailingBlankLines = 64;

constexpr std::string_view kFieldNames[] = {
    "time", "i", "x", "y", "vx", "vy", "pair_collisions", "wall_collisions"};

bool is_digits(std::string_view s) {
  if (s.empty()) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

// The fields of a line split at spaces and tabs, at most kMaxFields (one more than a line has,
// to tell a line with too many); a CR before the LF is a line end.
constexpr std::size_t kMaxFields = 9;
struct Fields {
  std::array<std::string_view, kMaxFields> at;
  std::size_t size = 0;
  bool more = false;  // beyond kMaxFields
};

Fields split_fields(std::string_view line) {
  Fields fields;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::size_t at = 0;
  while (at < line.size()) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
    std::size_t end = at;
    while (end < line.size() && line[end] != ' ' && line[end] != '\t') ++end;
    if (end > at) {
      if (fields.size == kMaxFields) {
        fields.more = true;
        break;
      }
      fields.at[fields.size++] = line.substr(at, end - at);
    }
    at = end;
  }
  return fields;
}

bool parse_integer(std::string_view field, std::int64_t& value) {
  if (!is_digits(field.substr(field.starts_with('-') ? 1 : 0))) return false;
  const auto [stop, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  return ec == std::errc() && stop == field.data() + field.size();
}

}  // namespace

PrintedTimes::PrintedTimes(const Scene& scene)
    : steps_(scene.steps), print_(scene.mode == OutputMode::print) {}

std::uint64_t PrintedTimes::count() const {
  return print_ ? static_cast<std::uint64_t>(steps_) + 1 : 2;
}

std::int64_t PrintedTimes::operator[](std::uint64_t k) const {
  return print_ ? static_cast<std::int64_t>(k) : (k == 0 ? 0 : steps_);
}

bool parse_fixed8(std::string_view field, double& value) {
  const bool negative = field.starts_with('-');
  const std::string_view digits = field.substr(negative ? 1 : 0);
  const std::size_t point = digits.size() >= 10 ? digits.size() - 9 : 0;
  if (point == 0 || digits[point] != '.') {
    for (const auto& [text, v] :
         {std::pair<std::string_view, double>{"nan", NAN}, {"inf", INFINITY}})
      if (digits == text) {
        value = negative ? -v : v;
        return true;
      }
    return false;
  }
  // Below 2^53 the digits without the point are an exact integer m, and m / 1e8 (two exact
  // doubles) is the correctly rounded value of the decimal, as strtod gives it. The 8 decimals
  // are read at once (8 bytes as one integer: the test and the conversion of simdjson).
  std::uint64_t eight;
  std::memcpy(&eight, digits.data() + point + 1, 8);
  bool valid = ((eight & 0xF0F0F0F0F0F0F0F0) |
                (((eight + 0x0606060606060606) & 0xF0F0F0F0F0F0F0F0) >> 4)) == 0x3333333333333333;
  eight = (eight & 0x0F0F0F0F0F0F0F0F) * 2561 >> 8;
  eight = (eight & 0x00FF00FF00FF00FF) * 6553601 >> 16;
  eight = (eight & 0x0000FFFF0000FFFF) * 42949672960001 >> 32;
  std::uint64_t m = 0;
  for (std::size_t k = 0; k < point; ++k) {
    const unsigned d = static_cast<unsigned char>(digits[k]) - '0';
    valid &= d <= 9;
    m = m * 10 + d;
  }
  m = m * 100000000 + eight;
  if (!valid) return false;
  if (point <= 7) {
    value = static_cast<double>(m) / 1e8;
  } else {
    const auto [stop, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec != std::errc() || stop != digits.data() + digits.size()) return false;
  }
  if (negative) value = -value;
  return true;
}

OutputReader::OutputReader(const std::string& path, const Scene& scene)
    : source_(path == "-" ? "<stdin>" : path),
      n_(scene.size()),
      times_(scene),
      buffer_(std::size_t{1} << 20) {
  if (path == "-") {
    file_ = stdin;
  } else {
    file_ = std::fopen(path.c_str(), "rb");
    owned_ = true;
    // A file that is not there is a usage error, not an output of the wrong format.
    if (!file_) throw InputError(fmt::format("{}: cannot open: {}", source_, std::strerror(errno)));
    struct stat st {};
    if (fstat(fileno(file_), &st) == 0 && S_ISDIR(st.st_mode)) {
      std::fclose(file_);
      throw InputError(fmt::format("{}: is a directory, not a program's output", source_));
    }
  }
}

OutputReader::~OutputReader() {
  if (owned_ && file_) std::fclose(file_);
}

void OutputReader::fail(const std::string& problem) const {
  throw MalformedOutput(fmt::format("{}:{}: {}", source_, line_, problem), line_);
}

bool OutputReader::read_line(std::string_view& line) {
  for (;;) {
    const char* at = buffer_.data() + begin_;
    const auto* nl = static_cast<const char*>(std::memchr(at, '\n', end_ - begin_));
    const std::size_t length = nl ? static_cast<std::size_t>(nl - at) + 1 : end_ - begin_;
    if (length > kMaxLineBytes || (!nl && eof_ && length > 0)) {
      ++line_;
      if (length > kMaxLineBytes)
        fail(fmt::format("line: longer than {} bytes, its line end included", kMaxLineBytes));
      line = {at, length};  // the last line, without a line end
      begin_ = end_;
      return true;
    }
    if (nl) {
      ++line_;
      line = {at, length - 1};
      begin_ += length;
      return true;
    }
    if (eof_) return false;
    std::memmove(buffer_.data(), at, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
    const std::size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    if (got == 0) {
      if (std::ferror(file_)) fail(fmt::format("read error: {}", std::strerror(errno)));
      eof_ = true;
    }
    end_ += got;
  }
}

std::string OutputReader::lines() const {
  // N (S + 1) passes 2^64 for S near the limits: counted in 128 bits.
  return fmt::format("{}", static_cast<unsigned __int128>(n_) * times_.count());
}

bool OutputReader::next(Block& block) {
  if (next_block_ == times_.count()) {
    std::string_view line;
    for (int blank = 0; read_line(line);) {
      if (split_fields(line).size > 0)
        fail(
            fmt::format("expected the end of the output after {} lines (N = {} per printed "
                        "time unit, {} time units), got {}",
                        lines(), n_, times_.count(), quoted(line)));
      if (++blank > kMaxTrailingBlankLines)
        fail(fmt::format("more than {} blank lines after the last state line",
                         kMaxTrailingBlankLines));
    }
    return false;
  }
  const std::int64_t time = times_[next_block_];
  const bool final = ++next_block_ == times_.count();
  const std::size_t want = final ? 8 : 6;
  block.time = time;
  block.final = final;
  block.bytes.clear();
  std::vector<std::size_t>& starts = starts_;
  starts.resize(n_ + 1);
  // The block's lines first, then their fields: the bytes move while they grow. An output that
  // ends early has its lines read so far checked first, so the first bad line is named.
  std::string_view line;
  std::size_t got = 0;
  for (; got < n_ && read_line(line); ++got) {
    starts[got] = block.bytes.size();
    block.bytes.insert(block.bytes.end(), line.begin(), line.end());
  }
  for (std::size_t i = got; i <= n_; ++i) starts[i] = block.bytes.size();
  if (block.state.size() != n_) block.state = Particles(n_);
  block.text.resize(4 * n_);
  const std::string_view all(block.bytes.data(), block.bytes.size());
  const std::int64_t end_line = line_;
  for (std::size_t i = 0; i < got; ++i) {
    line_ = end_line - static_cast<std::int64_t>(got - 1 - i);  // for the messages
    const Fields split = split_fields(all.substr(starts[i], starts[i + 1] - starts[i]));
    const auto& fields = split.at;
    const auto shape = [&] {
      return fmt::format("`{} {} x y vx vy{}`", time, i,
                         final ? " pair_collisions wall_collisions" : "");
    };
    if (split.size != want || split.more)
      fail(fmt::format("expected {} fields {}, got {}{}", want, shape(), split.size,
                       split.more ? " or more" : ""));
    std::int64_t value = 0;
    if (!parse_integer(fields[0], value) || value != time)
      fail(fmt::format("time: expected {} {}, got {}", time, shape(), quoted(fields[0])));
    if (!parse_integer(fields[1], value) || value != static_cast<std::int64_t>(i))
      fail(fmt::format("i: expected particle {} (lines in index order) {}, got {}", i, shape(),
                       quoted(fields[1])));
    double* values[] = {&block.state.x[i], &block.state.y[i], &block.state.vx[i],
                        &block.state.vy[i]};
    for (int f = 0; f < 4; ++f) {
      if (!parse_fixed8(fields[2 + f], *values[f]))
        fail(
            fmt::format("{}: expected a number as %.8f prints it (digits, a point, 8 decimals), "
                        "got {}",
                        kFieldNames[2 + f], quoted(fields[2 + f])));
      block.text[4 * i + f] = fields[2 + f];
    }
    std::uint64_t* counts[] = {&block.state.pair_collisions[i], &block.state.wall_collisions[i]};
    for (std::size_t f = 6; f < want; ++f) {
      const auto [stop, ec] =
          std::from_chars(fields[f].data(), fields[f].data() + fields[f].size(), *counts[f - 6]);
      if (!is_digits(fields[f]) || ec != std::errc() || stop != fields[f].data() + fields[f].size())
        fail(fmt::format("{}: expected a count (decimal digits), got {}", kFieldNames[f],
                         quoted(fields[f])));
    }
    if (!final) block.state.pair_collisions[i] = block.state.wall_collisions[i] = 0;
  }
  line_ = end_line;
  if (got < n_)
    fail(
        fmt::format("the output ends after {} lines; expected {} lines (N = {} per printed time "
                    "unit, {} time units), next `{} {} x y vx vy{}`",
                    line_, lines(), n_, times_.count(), time, got,
                    final ? " pair_collisions wall_collisions" : ""));
  return true;
}

}  // namespace particle::check
