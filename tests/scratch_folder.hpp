#pragma once
// A folder of the test process's own under the system's temporary folder, removed when the
// process ends: ctest runs each test as a process of its own, so files left per test would pile
// up in /tmp.
#include <fmt/format.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace test_support {

inline const std::filesystem::path& scratch_folder(const char* prefix) {
  struct Folder {
    std::filesystem::path path;
    explicit Folder(const char* prefix)
        : path(std::filesystem::temp_directory_path() / fmt::format("{}-{}", prefix, getpid())) {
      std::filesystem::create_directories(path);
    }
    ~Folder() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Folder folder(prefix);
  return folder.path;
}

}  // namespace test_support
