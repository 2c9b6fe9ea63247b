// State lines into large buffers, one fwrite per megabyte: print mode writes N*(S+1) lines and
// the 1M-particle scene 2M lines, so per-line stdio calls or printf would dominate a fast run.
// A line's four doubles go through format_four_fixed8 (format_fixed8 one at a time where it
// cannot: exact `%.8f`, see io/fixed8.hpp). A state of more than a few hundred lines is formatted
// by OpenMP tasks in rounds of four chunks per thread, then written in order: the same bytes
// whatever the thread count, and memory stays at one round of chunks.
#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "io/fixed8.hpp"
#include "particle/io.hpp"
#include "particle/options.hpp"

namespace particle {

char* print_fixed8(char* out, double v) { return detail::format_fixed8(out, v); }

// Defined before its caller below, the print loop, so that the compiler can inline it there.
char* print_state_values(char* out, double x, double y, double vx, double vy) {
  if (!detail::format_four_fixed8(out, x, y, vx, vy))
    for (const double v : {x, y, vx, vy}) {
      *out = ' ';
      out = detail::format_fixed8(out + 1, v);
    }
  return out;
}

namespace {

constexpr std::size_t kFlushBytes = 1 << 20;
// Chunks of 128 to 16384 lines (8 kB to 1 MB of text): a task costs about a microsecond.
constexpr std::size_t kMinChunkLines = 128, kMaxChunkLines = 16384;
// Below this, threads cost more than they save: inside the simulation's parallel region, whose
// team waits at a barrier anyway (print mode); and, higher, outside it, where a team of the
// writer's own must start and then spins idle beside the serial work that follows. At N = 20,000
// and S = 0, T = 2 formatting the two states on its own team took 27 against 12 ms for the whole
// process (median of 25, 2-core AMD EPYC VM), and at N = 10^6 it gained nothing there.
constexpr std::size_t kParallelLines = 512;
constexpr std::size_t kOwnTeamLines = std::size_t{1} << 17;
// Longest line: a time label, a 20-character index, four doubles, two counts, separators.
constexpr std::size_t kMaxTimeChars = 32;  // an integer step, or time_label()'s shortest double
constexpr std::size_t kMaxLineChars = kMaxTimeChars + 3 * 21 + 4 * kMaxFixed8Chars;

char* write_integer(char* out, std::int64_t v) {
  *out = '-';
  out += v < 0;
  return detail::write_decimal(
      out, v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v));
}

// A line's start `time i`, copied as one fixed-size block (a short copy of variable length costs
// more than the rest of the line's text save the doubles). The index counts up in its decimal
// text, a carry every tenth line, instead of being converted anew: 7 of 30 ns per line.
class LineStart {
 public:
  static constexpr std::size_t kBytes = 64;  // > kMaxTimeChars + 1 + 20 digits, < kMaxLineChars

  LineStart(std::string_view time, std::size_t i) {
    const std::size_t label = std::min(time.size(), kMaxTimeChars);
    std::memcpy(text_, time.data(), label);
    text_[label] = ' ';
    digits_ = label + 1;
    size_ = static_cast<std::size_t>(detail::write_decimal(text_ + digits_, i) - text_);
  }

  char* write(char* out) const {
    std::memcpy(out, text_, kBytes);
    return out + size_;
  }

  // To the next index.
  void next() {
    std::size_t k = size_;
    while (k > digits_ && text_[k - 1] == '9') text_[--k] = '0';
    if (k > digits_) {
      ++text_[k - 1];
    } else {  // all nines: a 1 and one more zero
      text_[digits_] = '1';
      text_[size_++] = '0';
    }
  }

 private:
  char text_[kBytes];
  std::size_t digits_;  // where the index starts
  std::size_t size_;
};

// `time i x y vx vy` and, for the final state, ` pair_collisions wall_collisions`.
char* format_line(char* out, const LineStart& start, std::size_t i, const Particles& p,
                  bool final) {
  out = print_state_values(start.write(out), p.x[i], p.y[i], p.vx[i], p.vy[i]);
  if (final) {
    *out++ = ' ';
    out = detail::write_decimal(out, p.pair_collisions[i]);
    *out++ = ' ';
    out = detail::write_decimal(out, p.wall_collisions[i]);
  }
  *out++ = '\n';
  return out;
}

// Appends lines [begin, end) to `buffer` from `used` on, growing it as needed; returns the new
// used size. Calls `full(used)` (which returns the new used size) whenever kFlushBytes is passed.
template <class Full>
std::size_t append_lines(std::vector<char>& buffer, std::size_t used, std::string_view time,
                         const Particles& p, bool final, std::size_t begin, std::size_t end,
                         Full full) {
  LineStart start(time, begin);
  for (std::size_t i = begin; i < end; ++i, start.next()) {
    if (buffer.size() - used < kMaxLineChars) buffer.resize(2 * buffer.size() + kMaxLineChars);
    used = format_line(buffer.data() + used, start, i, p, final) - buffer.data();
    if (used >= kFlushBytes) used = full(used);
  }
  return used;
}

}  // namespace

std::string_view print_state_lines(std::vector<char>& buffer, std::int64_t step,
                                   const Particles& p) {
  char label[24];
  const std::string_view time(label, static_cast<std::size_t>(write_integer(label, step) - label));
  const std::size_t used =
      append_lines(buffer, 0, time, p, false, 0, p.size(), [](std::size_t used) { return used; });
  return {buffer.data(), used};
}

// The buffer grows with what is written (append_lines), to kFlushBytes and a line at most: sized
// up front, it cost every run a megabyte zeroed and 256 pages faulted in (a one-particle run now
// takes 156 page faults in all: issue 58), for the few lines most runs write.
StateWriter::StateWriter(std::FILE* out, int threads)
    : out_(out), threads_(resolve_threads(threads)) {}

StateWriter::~StateWriter() { flush(); }

std::string time_label(double time) {
  if (time == std::floor(time) && std::fabs(time) < 0x1p63)
    return std::to_string(static_cast<std::int64_t>(time));
  return fmt::format("{}", time);  // the shortest text that reads back as the same double
}

void StateWriter::write(std::int64_t step, const Particles& p) {
  char label[24];
  write_lines({label, static_cast<std::size_t>(write_integer(label, step) - label)}, p, false);
}

void StateWriter::write_final(std::string_view time, const Particles& p) {
  write_lines(time, p, true);
}

void StateWriter::write_lines(std::string_view time, const Particles& p, bool final) {
  const std::size_t n = p.size();
  const auto write_out = [this](std::size_t used) {
    std::fwrite(buffer_.data(), 1, used, out_);
    return std::size_t{0};
  };
  if (threads_ == 1 || n < (omp_in_parallel() ? kParallelLines : kOwnTeamLines)) {
    used_ = append_lines(buffer_, used_, time, p, final, 0, n, write_out);
    return;
  }
  used_ = write_out(used_);  // keep the order: what is buffered goes first
  // Several chunks per thread, so that a thread the OS deschedules holds up little.
  const std::size_t per_round = 4 * static_cast<std::size_t>(threads_);
  const std::size_t lines = std::clamp(n / per_round, kMinChunkLines, kMaxChunkLines);
  chunks_.resize(per_round);
  std::vector<std::size_t> sizes(per_round);
  for (std::size_t round = 0; round < n; round += per_round * lines) {
    const auto format_round = [&] {
      for (std::size_t c = 0; c < per_round; ++c) {
        const std::size_t begin = std::min(n, round + c * lines);
#pragma omp task default(shared) firstprivate(c, begin)
        sizes[c] = append_lines(chunks_[c], 0, time, p, final, begin, std::min(n, begin + lines),
                                [](std::size_t used) { return used; });
      }
#pragma omp taskwait
    };
    // Tasks, not a worksharing loop: print mode calls this from one thread inside the
    // simulation's parallel region, where the team's other threads take the tasks while they wait
    // at its barrier. Outside a parallel region, a team of our own does.
    if (omp_in_parallel()) {
      format_round();
    } else {
#pragma omp parallel num_threads(threads_)
#pragma omp single
      format_round();
    }
    // A chunk past the last line was never allocated: its data() is null, which fwrite may not
    // take even for 0 bytes (UBSan: "null pointer passed as argument 1").
    for (std::size_t c = 0; c < per_round; ++c)
      if (sizes[c] > 0) std::fwrite(chunks_[c].data(), 1, sizes[c], out_);
  }
}

void StateWriter::flush() {
  if (used_ > 0) std::fwrite(buffer_.data(), 1, used_, out_);
  used_ = 0;
  std::fflush(out_);
}

}  // namespace particle
