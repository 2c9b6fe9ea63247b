#include "run/caches.hpp"

#include <filesystem>
#include <fstream>

namespace psweep {
namespace {

std::string first_line(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

}  // namespace

std::uint64_t parse_size(const std::string& text) {
  std::size_t used = 0;
  std::uint64_t value = 0;
  try {
    value = std::stoull(text, &used);
  } catch (const std::exception&) {
    return 0;
  }
  const std::string unit = text.substr(used);
  if (unit.empty()) return value;
  if (unit == "K") return value << 10;
  if (unit == "M") return value << 20;
  if (unit == "G") return value << 30;
  return 0;
}

std::vector<Cache> read_caches(const std::string& root) {
  std::vector<Cache> caches;
  for (int index = 0;; ++index) {
    const std::filesystem::path dir =
        std::filesystem::path(root) / ("index" + std::to_string(index));
    if (!std::filesystem::is_directory(dir)) break;
    Cache c;
    c.level = std::atoi(first_line(dir / "level").c_str());
    c.type = first_line(dir / "type");
    c.size_bytes = parse_size(first_line(dir / "size"));
    c.line_bytes = std::atoi(first_line(dir / "coherency_line_size").c_str());
    c.ways = std::atoi(first_line(dir / "ways_of_associativity").c_str());
    c.shared_cpu_list = first_line(dir / "shared_cpu_list");
    caches.push_back(c);
  }
  return caches;
}

std::uint64_t data_cache_bytes(const std::vector<Cache>& caches, int level) {
  int wanted = level;
  if (wanted == 0)
    for (const Cache& c : caches) wanted = std::max(wanted, c.level);
  std::uint64_t bytes = 0;
  for (const Cache& c : caches)
    if (c.level == wanted && c.type != "Instruction") bytes = std::max(bytes, c.size_bytes);
  return bytes;
}

}  // namespace psweep
