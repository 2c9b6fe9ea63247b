// State lines through fmt into one large buffer: print mode writes N*(S+1) lines, and per-line
// stdio calls would dominate a fast run.
#include <fmt/format.h>

#include <iterator>

#include "particle/io.hpp"

namespace particle {

namespace {
constexpr std::size_t kFlushBytes = 1 << 20;
}

StateWriter::StateWriter(std::FILE* out) : out_(out) { buffer_.reserve(2 * kFlushBytes); }

StateWriter::~StateWriter() { flush(); }

void StateWriter::write(std::int64_t step, const Particles& p) {
  auto out = std::back_inserter(buffer_);
  for (std::size_t i = 0; i < p.size(); ++i) {
    fmt::format_to(out, "{} {} {:.8f} {:.8f} {:.8f} {:.8f}\n", step, i, p.x[i], p.y[i], p.vx[i],
                   p.vy[i]);
    if (buffer_.size() >= kFlushBytes) flush();
  }
}

void StateWriter::write_final(std::int64_t step, const Particles& p) {
  auto out = std::back_inserter(buffer_);
  for (std::size_t i = 0; i < p.size(); ++i) {
    fmt::format_to(out, "{} {} {:.8f} {:.8f} {:.8f} {:.8f} {} {}\n", step, i, p.x[i], p.y[i],
                   p.vx[i], p.vy[i], p.pair_collisions[i], p.wall_collisions[i]);
    if (buffer_.size() >= kFlushBytes) flush();
  }
}

void StateWriter::flush() {
  if (!buffer_.empty()) std::fwrite(buffer_.data(), 1, buffer_.size(), out_);
  buffer_.clear();
  std::fflush(out_);
}

}  // namespace particle
