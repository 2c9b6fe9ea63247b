#include "whole_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "particle/io.hpp"

namespace lab {

WholeFile::WholeFile(std::string path, std::string_view option)
    : path_(std::move(path)), option_(option), target_(particle::output_target(path_)) {
  if (target_.kind == particle::OutputTarget::Kind::unusable)
    throw particle::InputError(
        fmt::format("{}{} {}; name a file", prefix(), path_, target_.problem));
  if (!target_.atomic()) {
    temp_ = target_.path;
    // Opened only when written: a FIFO's open waits for its reader.
    if (access(temp_.c_str(), W_OK) != 0) fail(errno);
    return;
  }
  temp_ = fmt::format("{}.tmp-{}", target_.path, getpid());
  get();
  discard();
}

WholeFile::~WholeFile() {
  if (file_) discard();
}

void WholeFile::discard() {
  std::fclose(file_);
  file_ = nullptr;
  if (target_.atomic()) std::remove(temp_.c_str());
}

std::FILE* WholeFile::get() {
  // In place, appended: /dev/stdout redirected to a file already holds psim's states.
  if (!file_) file_ = std::fopen(temp_.c_str(), target_.atomic() ? "we" : "ae");
  if (!file_) fail(errno);
  return file_;
}

void WholeFile::commit() {
  std::FILE* file = get();
  file_ = nullptr;
  const bool written = std::fflush(file) == 0 && !std::ferror(file);
  const int error = errno;
  const bool closed = std::fclose(file) == 0;
  if (!target_.atomic()) {
    if (!written || !closed) fail(written ? errno : error);
    return;
  }
  if (!closed || !written || std::rename(temp_.c_str(), target_.path.c_str()) != 0) {
    const int last = written ? errno : error;
    std::remove(temp_.c_str());
    fail(last);
  }
}

void WholeFile::fail(int error) const {
  throw particle::InputError(
      fmt::format("{}cannot write {} ({})", prefix(), path_, std::strerror(error)));
}

std::string WholeFile::prefix() const { return option_.empty() ? "" : option_ + ": ";
}

}  // namespace lab
