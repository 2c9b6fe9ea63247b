// State lines into large buffers, one fwrite per megabyte: print mode writes N*(S+1) lines and
// the 1M-particle scene 2M lines, so per-line stdio calls or printf would dominate a fast run.
// Doubles go through format_fixed8 (exact `%.8f`, see fixed8.hpp). Outside a parallel region a
// large state is formatted by all threads in rounds of one chunk per thread, then written in
// order: the output is the same bytes whatever the thread count, and memory stays at one chunk
// per thread. Inside the simulation's parallel region (print mode's observer runs on one thread
// while the others wait) lines are formatted serially.
#include <omp.h>

#include <algorithm>

#include "fixed8.hpp"
#include "particle/io.hpp"

namespace particle {

namespace {

constexpr std::size_t kFlushBytes = 1 << 20;
constexpr std::size_t kChunkLines = 16384;     // about 1 MB of text per chunk
constexpr std::size_t kParallelLines = 32768;  // below this, threads cost more than they save
// Longest line: two 20-character integers, four doubles, two counts, separators.
constexpr std::size_t kMaxLineChars = 4 * 21 + 4 * detail::kMaxFixed8Chars;

char* write_integer(char* out, std::int64_t v) {
  *out = '-';
  out += v < 0;
  return detail::write_decimal(
      out, v < 0 ? 0 - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v));
}

// `step i x y vx vy` and, for the final state, ` pair_collisions wall_collisions`.
char* format_line(char* out, std::int64_t step, std::size_t i, const Particles& p, bool final) {
  out = write_integer(out, step);
  *out++ = ' ';
  out = detail::write_decimal(out, i);
  for (const std::vector<double>* v : {&p.x, &p.y, &p.vx, &p.vy}) {
    *out++ = ' ';
    out = detail::format_fixed8(out, (*v)[i]);
  }
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
std::size_t append_lines(std::vector<char>& buffer, std::size_t used, std::int64_t step,
                         const Particles& p, bool final, std::size_t begin, std::size_t end,
                         Full full) {
  for (std::size_t i = begin; i < end; ++i) {
    if (buffer.size() - used < kMaxLineChars) buffer.resize(2 * buffer.size() + kMaxLineChars);
    used = format_line(buffer.data() + used, step, i, p, final) - buffer.data();
    if (used >= kFlushBytes) used = full(used);
  }
  return used;
}

}  // namespace

StateWriter::StateWriter(std::FILE* out, int threads)
    : out_(out), threads_(threads > 0 ? threads : omp_get_max_threads()) {
  buffer_.resize(kFlushBytes + kMaxLineChars);
}

StateWriter::~StateWriter() { flush(); }

void StateWriter::write(std::int64_t step, const Particles& p) { write_lines(step, p, false); }

void StateWriter::write_final(std::int64_t step, const Particles& p) { write_lines(step, p, true); }

void StateWriter::write_lines(std::int64_t step, const Particles& p, bool final) {
  const std::size_t n = p.size();
  const auto write_out = [this](std::size_t used) {
    std::fwrite(buffer_.data(), 1, used, out_);
    return std::size_t{0};
  };
  if (threads_ == 1 || n < kParallelLines || omp_in_parallel()) {
    used_ = append_lines(buffer_, used_, step, p, final, 0, n, write_out);
    return;
  }
  used_ = write_out(used_);  // keep the order: what is buffered goes first
  chunks_.resize(static_cast<std::size_t>(threads_));
  for (std::size_t round = 0; round < n; round += threads_ * kChunkLines) {
    std::vector<std::size_t> sizes(chunks_.size(), 0);
#pragma omp parallel for num_threads(threads_) schedule(static, 1)
    for (std::size_t c = 0; c < chunks_.size(); ++c) {
      const std::size_t begin = std::min(n, round + c * kChunkLines);
      sizes[c] =
          append_lines(chunks_[c], 0, step, p, final, begin, std::min(n, begin + kChunkLines),
                       [](std::size_t used) { return used; });
    }
    for (std::size_t c = 0; c < chunks_.size(); ++c)
      std::fwrite(chunks_[c].data(), 1, sizes[c], out_);
  }
}

void StateWriter::flush() {
  if (used_ > 0) std::fwrite(buffer_.data(), 1, used_, out_);
  used_ = 0;
  std::fflush(out_);
}

}  // namespace particle
