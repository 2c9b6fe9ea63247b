// Reading the 2019 output format (see particle/output_text.hpp) on the scene reader's lines.
#include "particle/output_text.hpp"

#include <fmt/format.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>

#include "io/fixed8.hpp"
#include "io/scene_text.hpp"
#include "particle/io.hpp"

namespace particle {

namespace {

// Blank lines after the last state line: a trailing newline or two, never an endless stream.
constexpr int kMaxTrailingBlankLines = 64;

constexpr std::string_view kFieldNames[] = {
    "time", "i", "x", "y", "vx", "vy", "pair_collisions", "wall_collisions"};

// `path` opened for OutputReader; empty for stdin ("-"). A file that is not there is a usage
// error, not an output of the wrong format.
std::unique_ptr<std::istream> open_output(const std::string& path) {
  if (path == "-") return nullptr;
  struct stat st {};
  if (stat(path.c_str(), &st) != 0)
    throw InputError(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
  if (S_ISDIR(st.st_mode))
    throw InputError(fmt::format("{}: is a directory, not a program's output", path));
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) throw InputError(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
  return file;
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
  const std::uint64_t decimals = detail::load8(digits.data() + point + 1);
  if (!detail::eight_digits(decimals)) return false;
  if (point <= 7) {
    // The digits before the point in one word: the 8 bytes from the start moved up past as many
    // '0's as make them 8 digits (the point and decimals fall off). The digits without the point
    // are then an exact integer m < 10^15 < 2^53, and m / 1e8 (two exact doubles) is the
    // correctly rounded value of the decimal, as strtod gives it.
    const std::uint64_t integer =
        detail::load8(digits.data()) << (8 * (8 - point)) | 0x3030303030303030 >> (8 * point);
    if (!detail::eight_digits(integer)) return false;
    value = static_cast<double>(std::uint64_t{detail::eight_digits_value(integer)} * 100000000 +
                                detail::eight_digits_value(decimals)) /
            1e8;
  } else {
    for (std::size_t k = 0; k < point; ++k)
      if (static_cast<unsigned>(digits[k] - '0') > 9) return false;
    const auto [stop, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec != std::errc() || stop != digits.data() + digits.size()) return false;
  }
  if (negative) value = -value;
  return true;
}

OutputReader::OutputReader(const std::string& path, const Scene& scene)
    : OutputReader(open_output(path), path == "-" ? "<stdin>" : path, scene) {}

OutputReader::OutputReader(std::unique_ptr<std::istream> in, const std::string& source,
                           const Scene& scene)
    : in_(std::move(in)), scene_(scene), n_(scene.size()), times_(scene) {
  reader_ = std::make_unique<detail::LineReader>(in_ ? *in_ : std::cin, source);
}

OutputReader::~OutputReader() = default;

void OutputReader::fail(const std::string& problem) const {
  throw MalformedOutput(fmt::format("{}:{}: {}", reader_->source(), reader_->line(), problem),
                        reader_->line());
}

std::string OutputReader::lines() const {
  // N (S + 1) passes 2^64 for S near the limits: counted in 128 bits.
  return fmt::format("{}", static_cast<detail::uint128>(n_) * times_.count());
}

bool OutputReader::next(Block& block, std::string_view expected) {
  try {
    if (next_block_ == times_.count()) {
      expect_end();
      return false;
    }
    return read_block(block, expected);
  } catch (const MalformedOutput&) {
    throw;
  } catch (const InputError& e) {
    // The line reader's own limits (a line too long, a read error): the output's fault.
    throw MalformedOutput(e.what(), reader_->line());
  }
}

void OutputReader::expect_end() {
  for (int blank = 0; reader_->next();) {
    if (reader_->count() > 0)
      fail(
          fmt::format("expected the end of the output after {} lines (N = {} per printed time "
                      "unit, {} time units), got {}",
                      lines(), n_, times_.count(), quoted(reader_->text())));
    if (++blank > kMaxTrailingBlankLines)
      fail(fmt::format("more than {} blank lines after the last state line",
                       kMaxTrailingBlankLines));
  }
}

bool OutputReader::starts_with_final_state() {
  if (scene_.mode != OutputMode::perf || n_ == 0 || !reader_->next()) return false;
  pending_ = true;
  std::int64_t time = 0;
  return reader_->count() == 8 && detail::try_parse_integer(reader_->field(0), time) &&
         time == times_[1] && time != 0;
}

bool OutputReader::repeats_final_time() {
  if (scene_.mode != OutputMode::print || n_ == 0 || !reader_->next()) return false;
  pending_ = true;
  std::int64_t time = 0;
  return reader_->count() == 6 && detail::try_parse_integer(reader_->field(0), time) &&
         time == times_[times_.count() - 1];
}

void OutputReader::expect_same_as_repeated(const Block& block, const std::vector<char>& bytes,
                                           const std::vector<std::size_t>& ends) const {
  for (std::size_t k = 0, begin = 0; k < ends.size(); begin = ends[k++]) {
    const std::string_view first(bytes.data() + begin + 1, ends[k] - begin - 1);
    if (first != block.text[k])
      fail(fmt::format(
          "time unit {} is printed twice (after its step, then as the final state "
          "with its counts) with different values: particle {}'s {} is {} then {}",
          block.time, k / 4, kFieldNames[2 + k % 4], quoted(first), quoted(block.text[k])));
  }
}

void OutputReader::scene_block(Block& block) {
  block.state = scene_.particles;
  block.bytes.resize(n_ * kMaxStateValuesChars);
  char* at = block.bytes.data();
  for (std::size_t i = 0; i < n_; ++i) {
    const double values[] = {block.state.x[i], block.state.y[i], block.state.vx[i],
                             block.state.vy[i]};
    for (std::size_t f = 0; f < 4; ++f) {
      *at = ' ';
      at = print_fixed8(at + 1, values[f]);
      ends_[4 * i + f] = static_cast<std::size_t>(at - block.bytes.data());
    }
  }
  text_views(block);
}

void OutputReader::text_views(Block& block) const {
  block.text.resize(4 * n_);
  for (std::size_t k = 0, begin = 0; k < ends_.size(); begin = ends_[k++])
    block.text[k] = {block.bytes.data() + begin + 1, ends_[k] - begin - 1};  // after its space
}

bool OutputReader::read_block(Block& block, std::string_view expected) {
  block.time = times_[next_block_];
  block.final = ++next_block_ == times_.count();
  block.as_expected = false;
  block.bytes.clear();
  ends_.resize(4 * n_);
  if (block.time == 0 && starts_with_final_state()) {
    final_only_ = true;
    scene_block(block);
    return true;
  }
  if (block.state.size() != n_) block.state = Particles(n_);
  if (block.final && block.time != 0 && repeats_final_time()) {
    final_repeated_ = true;
    read_state_lines(block, 6);
    std::vector<char> first;  // the first printing's text, set aside
    std::vector<std::size_t> first_ends;
    first.swap(block.bytes);
    first_ends = ends_;
    read_state_lines(block, 8);
    text_views(block);
    expect_same_as_repeated(block, first, first_ends);
    return true;
  }
  // Print mode's time units before the final one: no line is pending there (the two checks
  // above read ahead only at time 0 of perf mode and at the final time unit).
  std::size_t from = 0;
  if (!expected.empty() && !block.final && !pending_) {
    const std::size_t taken = take_as_expected(expected);
    if (taken == expected.size()) {
      block.as_expected = true;
      return true;
    }
    from = read_printed_lines(block, expected.substr(0, taken));
  }
  read_state_lines(block, block.final ? 8 : 6, from);
  text_views(block);  // last: the bytes moved while they grew
  return true;
}

// The output's next whole lines while they are `expected`'s, byte for byte, taken as read (one
// comparison of the buffered input, no line split); returns the bytes taken. Stops at the first
// line that differs, and at the end of what the reader may read (next() then says why).
std::size_t OutputReader::take_as_expected(std::string_view expected) {
  std::size_t taken = 0;
  while (taken < expected.size()) {
    const std::string_view input = reader_->whole_lines();
    const std::string_view want = expected.substr(taken);
    const std::size_t n = std::min(input.size(), want.size());
    std::size_t same = n;
    if (std::memcmp(input.data(), want.data(), n) != 0)
      same = static_cast<std::size_t>(
          std::mismatch(input.begin(), input.begin() + static_cast<std::ptrdiff_t>(n), want.begin())
              .first -
          input.begin());
    const std::size_t end = input.substr(0, same).rfind('\n');
    if (end == std::string_view::npos) break;
    const std::string_view lines = input.substr(0, end + 1);
    reader_->skip(lines, std::count(lines.begin(), lines.end(), '\n'));
    taken += lines.size();
    if (same < n) break;
  }
  return taken;
}

// The state lines `printed` holds, psim's own (print_state_lines), into the block from its first
// particle on; returns how many.
std::size_t OutputReader::read_printed_lines(Block& block, std::string_view printed) {
  std::size_t i = 0;
  std::vector<char> line;  // a line and the bytes LineFields::split may read after its start
  for (std::size_t begin = 0; begin < printed.size(); ++i) {
    const std::size_t end = printed.find('\n', begin);
    line.assign(printed.begin() + static_cast<std::ptrdiff_t>(begin),
                printed.begin() + static_cast<std::ptrdiff_t>(end));
    const std::size_t length = line.size();
    line.resize(length + detail::LineFields::kReadAhead);
    detail::LineFields fields;
    fields.split(line.data(), line.data() + length);
    read_line(block, i, 6, fields);
    begin = end + 1;
  }
  return i;
}

void OutputReader::read_printed(Block& block, std::string_view printed) {
  block.as_expected = false;
  block.bytes.clear();
  if (block.state.size() != n_) block.state = Particles(n_);
  ends_.resize(4 * n_);
  read_printed_lines(block, printed);
  text_views(block);
}

void OutputReader::read_state_lines(Block& block, std::size_t fields, std::size_t from) {
  for (std::size_t i = from; i < n_; ++i) {
    if (pending_)
      pending_ = false;
    else if (!reader_->next())
      fail(
          fmt::format("the output ends after {} lines; expected {} lines (N = {} per printed "
                      "time unit, {} time units), next `{} {} x y vx vy{}`",
                      reader_->line(), lines(), n_, times_.count(), block.time, i,
                      fields == 8 ? " pair_collisions wall_collisions" : ""));
    read_line(block, i, fields, reader_->fields());
  }
}

void OutputReader::read_line(Block& block, std::size_t i, std::size_t want,
                             const detail::LineFields& r) {
  const auto shape = [&] {
    return fmt::format("`{} {} x y vx vy{}`", block.time, i,
                       want == 8 ? " pair_collisions wall_collisions" : "");
  };
  if (static_cast<std::size_t>(r.count()) != want)
    fail(fmt::format("expected {} fields {}, got {}", want, shape(), r.count()));
  std::int64_t value = 0;
  if (!detail::try_parse_integer(r.field(0), value) || value != block.time)
    fail(fmt::format("time: expected {} {}, got {}", block.time, shape(), quoted(r.field(0))));
  if (!detail::try_parse_integer(r.field(1), value) || value != static_cast<std::int64_t>(i))
    fail(fmt::format("i: expected particle {} (lines in index order) {}, got {}", i, shape(),
                     quoted(r.field(1))));
  double* values[] = {&block.state.x[i], &block.state.y[i], &block.state.vx[i], &block.state.vy[i]};
  std::size_t length = 0;  // of the four values' texts
  for (int f = 0; f < 4; ++f) {
    const std::string_view text = r.field(2 + f);
    if (!parse_fixed8(text, *values[f]))
      fail(
          fmt::format("{}: expected a number as %.8f prints it (digits, a point, 8 decimals), "
                      "got {}",
                      kFieldNames[2 + f], quoted(text)));
    length += text.size();
  }
  // Each value after one space (Block::bytes): where the program separates them by single spaces
  // as psim does, the line holds them so already, and one copy takes the four.
  const std::string_view x = r.field(2), vy = r.field(5);
  const char* from = x.data() - 1;
  if (static_cast<std::size_t>(vy.data() + vy.size() - from) == length + 4 && *from == ' ' &&
      r.field(3).data()[-1] == ' ' && r.field(4).data()[-1] == ' ' && vy.data()[-1] == ' ') {
    std::size_t end = block.bytes.size();
    block.bytes.insert(block.bytes.end(), from, vy.data() + vy.size());
    for (int f = 0; f < 4; ++f) ends_[4 * i + f] = end += 1 + r.field(2 + f).size();
  } else {
    for (int f = 0; f < 4; ++f) {
      block.bytes.push_back(' ');
      block.bytes.insert(block.bytes.end(), r.field(2 + f).begin(), r.field(2 + f).end());
      ends_[4 * i + f] = block.bytes.size();
    }
  }
  std::uint64_t* counts[] = {&block.state.pair_collisions[i], &block.state.wall_collisions[i]};
  for (std::size_t f = 6; f < 8; ++f) {
    std::int64_t count = 0;
    if (f < want && (!detail::try_parse_integer(r.field(f), count) || count < 0))
      fail(fmt::format("{}: expected a count (decimal digits), got {}", kFieldNames[f],
                       quoted(r.field(f))));
    *counts[f - 6] = static_cast<std::uint64_t>(count);
  }
}

}  // namespace particle
