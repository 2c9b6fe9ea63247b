#pragma once
// The CS3210 2019 text format: N, L, r, S, print|perf, then optionally N lines `i x y vx vy`.
#include <cstdint>
#include <cstdio>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "particle/scene.hpp"

namespace particle {

// Bad user input: what() reads `SOURCE:LINE: FIELD: problem`.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `token` in double quotes for a message, with control, invisible and non-ASCII characters
// escaped (\t, \r, \xNN, \uFEFF) and more than kShownChars characters cut with an ellipsis and
// the full length: scene fields and psim's option values alike.
inline constexpr std::size_t kShownChars = 40;
std::string quoted(std::string_view token);

// The most bytes a line of the input may hold, its line end included: far more than five numbers
// need. The input as a whole may hold at most (N + 5) x kMaxLineBytes bytes (the header's N),
// blank lines included, so a device or pipe that never ends (/dev/zero, `yes`) is refused
// instead of read without end.
inline constexpr std::size_t kMaxLineBytes = 4096;

struct SpeedRange {
  double min = 0, max = 0;
};

struct RandomInit {
  std::uint64_t seed = 3210;
  std::optional<SpeedRange> speed;  // default: between L/(8r) and L/4
};

// The five header lines.
struct SceneHeader {
  std::int64_t n = 0;
  double L = 0, r = 0;
  std::int64_t steps = 0;
  OutputMode mode = OutputMode::perf;
};

// Reads only the header, with read_scene's rules and messages (psim --header).
SceneHeader read_scene_header(std::istream& in, const std::string& source);

// Reads a scene; without particle lines, places particles randomly with `init`. A large scene's
// particle lines are parsed on `threads` threads (0: OpenMP's default), with the same result and
// messages as on one.
Scene read_scene(std::istream& in, const std::string& source, const RandomInit& init,
                 int threads = 1);

// A time in time units as the output writes it: whole units as integers ("12"), anything else as
// the shortest decimal that reads back as the same double ("12.5").
std::string time_label(double time);

// Writer of state lines (`%.8f` doubles, byte-identical to printf's) through large buffers;
// output must not dominate print-mode runs. States of more than a few hundred lines are formatted
// by OpenMP tasks on `threads` threads (0: OpenMP's default), or, when called from inside a
// parallel region, by that region's team.
class StateWriter {
 public:
  explicit StateWriter(std::FILE* out, int threads = 0);
  ~StateWriter();
  void write(std::int64_t step, const Particles& p);  // `step i x y vx vy`
  // `time i x y vx vy pair_collisions wall_collisions`: the final state at `time`, the step S or
  // time_label() of where an interrupted run stopped.
  void write_final(std::string_view time, const Particles& p);
  void flush();

 private:
  void write_lines(std::string_view time, const Particles& p, bool final);

  std::FILE* out_;
  int threads_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
  std::vector<std::vector<char>> chunks_;  // one per thread, reused across rounds
};

}  // namespace particle
