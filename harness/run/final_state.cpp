// Final state: see final_state.hpp.
#include "run/final_state.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <sstream>
#include <utility>

namespace psweep {
namespace {

std::string normalised(const std::string& line) {
  std::istringstream in(line);
  std::string field, out;
  while (in >> field) out += (out.empty() ? "" : " ") + field;
  return out;
}

// A line as a message quotes it: at most 120 characters.
std::string quoted(const std::string& line) {
  return "`" + (line.size() > 120 ? line.substr(0, 117) + "..." : line) + "`";
}

}  // namespace

std::vector<std::string> final_state(const std::string& path, std::size_t n) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rbe"), std::fclose);
  if (!f || n == 0 || std::fseek(f.get(), 0, SEEK_END) != 0) return {};
  const long size = std::ftell(f.get());
  // From the end, a growing tail until it holds n lines (and the one before them, cut short).
  std::vector<std::string> lines;
  for (long tail = 4096;; tail *= 2) {
    const long from = std::max(0L, size - tail);
    std::string text(static_cast<std::size_t>(size - from), '\0');
    if (std::fseek(f.get(), from, SEEK_SET) != 0 ||
        std::fread(text.data(), 1, text.size(), f.get()) != text.size())
      return {};
    lines.clear();
    std::istringstream in(text);
    std::string line;
    bool first = from > 0;  // a line cut by the tail's start is not a line
    while (std::getline(in, line)) {
      if (std::exchange(first, false)) continue;
      if (auto kept = normalised(line); !kept.empty()) lines.push_back(std::move(kept));
    }
    if (lines.size() >= n || from == 0) break;
  }
  if (lines.size() > n) lines.erase(lines.begin(), lines.end() - static_cast<std::ptrdiff_t>(n));
  return lines;
}

std::optional<std::string> final_state_difference(const std::vector<std::string>& mine,
                                                  const std::vector<std::string>& reference,
                                                  const std::string& where) {
  for (std::size_t i = 0; i < std::min(mine.size(), reference.size()); ++i) {
    if (mine[i] == reference[i]) continue;
    std::istringstream fields(reference[i]);
    std::string step, particle;
    fields >> step >> particle;
    return fmt::format("particle {}: {} here, {} {}", particle, quoted(mine[i]),
                       quoted(reference[i]), where);
  }
  if (mine.size() != reference.size())
    return fmt::format("{} line{} of final state here, {} {}", mine.size(),
                       mine.size() == 1 ? "" : "s", reference.size(), where);
  return std::nullopt;
}

}  // namespace psweep
