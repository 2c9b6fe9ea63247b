#include "whole_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "particle/io.hpp"

namespace psim {

WholeFile::WholeFile(std::string path, std::string_view option)
    : path_(std::move(path)), temp_(fmt::format("{}.tmp-{}", path_, getpid())), option_(option) {
  file_ = std::fopen(temp_.c_str(), "w");
  if (!file_)
    throw particle::InputError(
        fmt::format("{}: cannot write {} ({})", option_, path_, std::strerror(errno)));
}

WholeFile::~WholeFile() {
  if (file_) {
    std::fclose(file_);
    std::remove(temp_.c_str());
  }
}

void WholeFile::commit() {
  const bool written = std::fflush(file_) == 0 && !std::ferror(file_);
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!written || !closed || std::rename(temp_.c_str(), path_.c_str()) != 0) {
    const int error = errno;
    std::remove(temp_.c_str());
    throw particle::InputError(
        fmt::format("{}: cannot write {} ({})", option_, path_, std::strerror(error)));
  }
}

}  // namespace psim
