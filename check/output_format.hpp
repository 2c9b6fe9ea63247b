#pragma once
// The output of a program under test, in the 2019 format psim writes (docs/psim.md, "Output"):
// N lines `t i x y vx vy` for t = 0 and, in print mode, every time unit up to S - 1, then N lines
// `S i x y vx vy pair_collisions wall_collisions`. Doubles as printf's `%.8f`; particles in index
// order. Read one time unit at a time through a fixed buffer, bounded by what the scene allows,
// so a program that prints without end costs neither memory nor more than that much reading.
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "particle/particles.hpp"
#include "particle/scene.hpp"

namespace particle::check {

// A line that breaks the format: what() reads `OUTPUT:LINE: problem (expected ...)`.
class MalformedOutput : public std::runtime_error {
 public:
  MalformedOutput(const std::string& message, std::int64_t line)
      : std::runtime_error(message), line_(line) {}
  std::int64_t line() const { return line_; }

 private:
  std::int64_t line_;
};

// One time unit as printed: the values, and each value's text for the exact comparison.
struct Block {
  std::int64_t time = 0;
  bool final = false;  // the last block: with collision counts
  Particles state;
  std::vector<std::string_view> text;  // 4 per particle: x, y, vx, vy; points into `bytes`
  std::vector<char> bytes;
};

// The time units a scene's output holds, in order: 0, then 1..S-1 in print mode, then S (final).
// Computed, not listed: the reader's memory follows what it has read, not S.
class PrintedTimes {
 public:
  explicit PrintedTimes(const Scene& scene);
  std::uint64_t count() const;
  std::int64_t operator[](std::uint64_t k) const;

 private:
  std::int64_t steps_;
  bool print_;
};

// Parses a `%.8f` field (optional '-', digits, '.', exactly 8 digits) into the double it reads
// as; printf's non-finite forms (nan, -nan, inf, -inf) read as NaN or infinity. False for
// anything else.
bool parse_fixed8(std::string_view field, double& value);

class OutputReader {
 public:
  // Reads `path` ("-": stdin) for `scene`; throws InputError if it cannot be opened or is a
  // directory.
  OutputReader(const std::string& path, const Scene& scene);
  ~OutputReader();
  OutputReader(const OutputReader&) = delete;
  OutputReader& operator=(const OutputReader&) = delete;

  // The next time unit into `block` (its buffers reused); false after the final one, once the
  // output has been checked to end there (blank lines allowed). Throws MalformedOutput.
  bool next(Block& block);

 private:
  bool read_line(std::string_view& line);  // false at the end of the output
  [[noreturn]] void fail(const std::string& problem) const;

  std::string source_;
  std::FILE* file_ = nullptr;
  bool owned_ = false;
  std::size_t n_;
  std::string lines() const;  // the lines a whole output has: N per printed time unit
  PrintedTimes times_;
  std::uint64_t next_block_ = 0;
  std::int64_t line_ = 0;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  std::vector<std::size_t> starts_;  // per particle line of a block: its offset in Block::bytes
};

}  // namespace particle::check
