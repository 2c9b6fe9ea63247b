#pragma once
// Shared by the checker's tests: a temporary folder, files written and read, running a program on
// a scene, checking it.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "../scratch_folder.hpp"
#include "check.hpp"

namespace check_test {

inline const std::filesystem::path& temp_dir() {
  return test_support::scratch_folder("check_tests");
}

inline std::string write_file(const std::string& name, const std::string& text) {
  const auto path = (temp_dir() / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

inline std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// `program [K] < scene > output`; returns the output's path.
inline std::string run_program(const std::string& program, const std::string& scene, int k = 1) {
  const std::string name = std::filesystem::path(program).filename().string() + "-" +
                           std::filesystem::path(scene).stem().string() + ".out";
  const auto out = (temp_dir() / name).string();
  const std::string command = fmt::format("'{}' {} < '{}' > '{}'", program, k, scene, out);
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return out;
}

// `reading`: the wall-stop reading required; none: every reading tried.
inline particle::check::Report check(const std::string& scene, const std::string& output, int k = 1,
                                     std::optional<particle::WallStop> reading = std::nullopt,
                                     std::optional<particle::Overlap> overlap = std::nullopt) {
  return particle::check::run_check({scene, output, k, reading, overlap});
}

}  // namespace check_test
