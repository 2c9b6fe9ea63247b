#pragma once
// Reading the 2019 output format that psim writes (docs/psim.md, "Output"), for `psim check` and
// any tool that reads a program's output: N lines `t i x y vx vy` for t = 0 and, in print mode,
// every time unit up to S - 1, then N lines `S i x y vx vy pair_collisions wall_collisions`.
// Doubles as printf's `%.8f`; particles in index order. The lines and fields are the scene
// reader's (io/scene_text.hpp: one set of rules for blanks, CRLF, signs and line lengths), read
// one time unit at a time through its fixed buffer, so a program that prints without end costs
// neither memory nor more reading than the scene allows.
#include <cstdint>
#include <istream>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "particle/particles.hpp"
#include "particle/scene.hpp"

namespace particle {

namespace detail {
class LineFields;
class LineReader;
}  // namespace detail

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
  // The output printed the lines the reader expected (OutputReader::next's `expected`), byte for
  // byte: the reader took them without parsing, and `state`, `text` and `bytes` are not this
  // block's (the caller has the state those lines print).
  bool as_expected = false;
  Particles state;
  std::vector<std::string_view> text;  // 4 per particle: x, y, vx, vy; points into `bytes`
  // Each value's text after one space: a particle's four read " x y vx vy" as psim prints them
  // (print_state_values), whatever blanks the program printed, so that one comparison takes all.
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

// What psim prints (io/fixed8.hpp: byte-identical to printf's `%.8f`), for tools that compare a
// program's text with it. Room each needs at `out`:
inline constexpr std::size_t kMaxFixed8Chars = 320;
inline constexpr std::size_t kMaxStateValuesChars = 4 * (kMaxFixed8Chars + 1);
// `%.8f` of v; returns the end.
char* print_fixed8(char* out, double v);
// " x y vx vy" as on a state line (each preceded by one space); returns the end.
char* print_state_values(char* out, double x, double y, double vx, double vy);
// The lines print mode writes for `p` at time unit `step` (`step i x y vx vy`, psim's own bytes),
// formatted into `buffer` (grown as needed, never shrunk: it is reused); returns them.
std::string_view print_state_lines(std::vector<char>& buffer, std::int64_t step,
                                   const Particles& p);

class OutputReader {
 public:
  // Reads `path` ("-": stdin) for `scene`; throws InputError if it cannot be opened or is a
  // directory.
  OutputReader(const std::string& path, const Scene& scene);
  // Reads `in`, named `source` in messages (a copy of stdin kept to be read again, for one).
  OutputReader(std::unique_ptr<std::istream> in, const std::string& source, const Scene& scene);
  ~OutputReader();
  OutputReader(const OutputReader&) = delete;
  OutputReader& operator=(const OutputReader&) = delete;

  // The next time unit into `block` (its buffers reused); false after the final one, once the
  // output has been checked to end there (blank lines allowed). Throws MalformedOutput.
  //
  // `expected`, where given, is what the caller expects a print-mode time unit before the final
  // one to print (print_state_lines): lines the output holds as those bytes are taken without
  // being split or parsed, which was most of the cost of checking an output that follows the
  // reference (the parse 53% of `psim check` on psim's own output, N = 1000, S = 1000).
  // Where every line is as expected, block.as_expected is set and nothing else of the block is
  // read; from the first line that is not, the block is read as without `expected`.
  //
  // A perf-mode output may hold the final state alone: the 2019 authors' programs print step 0
  // first, and two of two public student programs (and the output one of them commits) do not;
  // the handout leaves it open. Then the first block is the scene's own start, as printed.
  //
  // A print-mode output may print the last time unit twice: once as every time unit is printed
  // ("after each step"), then again as the final state with its counts ("at the end"), as a
  // public student program (bannified/cs3210-ass1) reads the handout; psim and the 2019 authors'
  // programs print it once. The two must hold the same values; the block is the second.
  bool next(Block& block, std::string_view expected = {});
  // Reads `block` again from `printed`, the lines it was taken as (next()'s `expected`): for a
  // caller that needs its values after all.
  void read_printed(Block& block, std::string_view printed);
  // Whether the output held the final state alone (known once the first block is read).
  bool final_only() const { return final_only_; }
  // Whether a print-mode output printed its last time unit twice (known once it is read).
  bool final_repeated() const { return final_repeated_; }

 private:
  bool read_block(Block& block, std::string_view expected);
  std::size_t take_as_expected(std::string_view expected);
  std::size_t read_printed_lines(Block& block, std::string_view printed);
  bool starts_with_final_state();
  bool repeats_final_time();
  void expect_same_as_repeated(const Block& block, const std::vector<char>& bytes,
                               const std::vector<std::size_t>& ends) const;
  void scene_block(Block& block);
  void text_views(Block& block) const;  // block.text from ends_ into block.bytes
  void expect_end();
  // Lines `from` to N - 1 of `fields` fields each.
  void read_state_lines(Block& block, std::size_t fields, std::size_t from = 0);
  void read_line(Block& block, std::size_t i, std::size_t fields, const detail::LineFields& line);
  [[noreturn]] void fail(const std::string& problem) const;
  std::string lines() const;  // the lines a whole output has: N per printed time unit

  std::unique_ptr<std::istream> in_;  // empty for stdin
  std::unique_ptr<detail::LineReader> reader_;
  const Scene& scene_;
  std::size_t n_;
  PrintedTimes times_;
  bool final_only_ = false;
  bool final_repeated_ = false;
  bool pending_ = false;  // a line already read (the first of a final-only output) comes next
  std::uint64_t next_block_ = 0;
  std::vector<std::size_t> ends_;  // of each value's text in Block::bytes, 4 per particle
};

}  // namespace particle
