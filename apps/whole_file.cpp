#include "whole_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "particle/io.hpp"

namespace psim {

WholeFile::WholeFile(std::string path, std::string_view option)
    : path_(std::move(path)), temp_(fmt::format("{}.tmp-{}", path_, getpid())), option_(option) {
  get();
  std::fclose(file_);
  file_ = nullptr;
  std::remove(temp_.c_str());
}

WholeFile::~WholeFile() {
  if (file_) {
    std::fclose(file_);
    std::remove(temp_.c_str());
  }
}

std::FILE* WholeFile::get() {
  if (!file_) file_ = std::fopen(temp_.c_str(), "w");
  if (!file_) fail(errno);
  return file_;
}

void WholeFile::commit() {
  std::FILE* file = get();
  file_ = nullptr;
  const bool written = std::fflush(file) == 0 && !std::ferror(file);
  const int error = errno;
  if (std::fclose(file) != 0 || !written || std::rename(temp_.c_str(), path_.c_str()) != 0) {
    const int last = written ? errno : error;
    std::remove(temp_.c_str());
    fail(last);
  }
}

void WholeFile::fail(int error) const {
  throw particle::InputError(
      fmt::format("{}: cannot write {} ({})", option_, path_, std::strerror(error)));
}

}  // namespace psim
