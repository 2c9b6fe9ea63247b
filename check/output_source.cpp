#include "output_source.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cassert>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <stdexcept>
#include <streambuf>

namespace particle::check {

// Stdin as read so far, in an unlinked temporary file, and the rest of stdin behind it. Readers
// take turns (one thread): whichever reads past the copy's end reads stdin and extends the copy.
class StdinCopy {
 public:
  StdinCopy() {
    const char* dir = std::getenv("TMPDIR");
    std::string name = fmt::format("{}/psim-check-stdin-XXXXXX", dir && *dir ? dir : "/tmp");
    fd_ = mkstemp(name.data());
    if (fd_ < 0) fail("cannot create " + name);
    unlink(name.c_str());
  }
  ~StdinCopy() { close(fd_); }
  StdinCopy(const StdinCopy&) = delete;
  StdinCopy& operator=(const StdinCopy&) = delete;

  // Up to n bytes of stdin from `offset` into `out`; fewer only at its end.
  std::size_t read_at(std::uint64_t offset, char* out, std::size_t n) {
    assert(offset <= size_);  // a reader reads in order, never past what some reader has read
    std::size_t got = 0;
    while (got < n && offset + got < size_) {
      const std::size_t want = std::min<std::uint64_t>(n - got, size_ - offset - got);
      const ssize_t k = pread(fd_, out + got, want, static_cast<off_t>(offset + got));
      if (k <= 0) fail("cannot read it back");  // the copy is read where it was written
      got += static_cast<std::size_t>(k);
    }
    if (got < n && !ended_) {
      const auto want = static_cast<std::streamsize>(n - got);
      const std::streamsize k = std::cin.rdbuf()->sgetn(out + got, want);
      ended_ = k < want;  // sgetn returns less only at the end (it waits on a pipe)
      append(out + got, static_cast<std::size_t>(k));
      got += static_cast<std::size_t>(k);
    }
    return got;
  }

 private:
  void append(const char* bytes, std::size_t n) {
    for (std::size_t done = 0; done < n;) {
      const ssize_t k = pwrite(fd_, bytes + done, n - done, static_cast<off_t>(size_ + done));
      if (k <= 0) fail("cannot write it");
      done += static_cast<std::size_t>(k);
    }
    size_ += n;
  }
  // Not an InputError: the output reader turns those into a malformed output, and this is no
  // fault of the output's.
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(
        fmt::format("<stdin>: its copy for the readings after the first (in TMPDIR, else /tmp): "
                    "{}: {}",
                    what, std::strerror(errno)));
  }

  int fd_ = -1;
  std::uint64_t size_ = 0;  // bytes of stdin read so far, all in the copy
  bool ended_ = false;
};

namespace {

// One reader's position in a StdinCopy.
class CopyBuffer : public std::streambuf {
 public:
  explicit CopyBuffer(std::shared_ptr<StdinCopy> copy) : copy_(std::move(copy)) {}

 protected:
  // The line reader asks for large blocks: straight into its buffer.
  std::streamsize xsgetn(char* out, std::streamsize n) override {
    const std::streamsize buffered = std::min<std::streamsize>(n, egptr() - gptr());
    std::memcpy(out, gptr(), static_cast<std::size_t>(buffered));
    gbump(static_cast<int>(buffered));
    const std::size_t got =
        copy_->read_at(at_, out + buffered, static_cast<std::size_t>(n - buffered));
    at_ += got;
    return buffered + static_cast<std::streamsize>(got);
  }
  int_type underflow() override {
    const std::size_t got = copy_->read_at(at_, buffer_, sizeof buffer_);
    at_ += got;
    setg(buffer_, buffer_, buffer_ + got);
    return got == 0 ? traits_type::eof() : traits_type::to_int_type(*gptr());
  }

 private:
  std::shared_ptr<StdinCopy> copy_;
  std::uint64_t at_ = 0;
  char buffer_[4096];
};

class CopyStream : public std::istream {
 public:
  explicit CopyStream(std::shared_ptr<StdinCopy> copy)
      : std::istream(nullptr), buffer_(std::move(copy)) {
    rdbuf(&buffer_);
  }

 private:
  CopyBuffer buffer_;
};

}  // namespace

OutputSource::OutputSource(std::string path, bool again) : path_(std::move(path)) {
  if (again && path_ == "-") copy_ = std::make_shared<StdinCopy>();
}

OutputSource::~OutputSource() = default;

std::unique_ptr<OutputReader> OutputSource::read(const Scene& scene) {
  if (!copy_) return std::make_unique<OutputReader>(path_, scene);
  return std::make_unique<OutputReader>(std::make_unique<CopyStream>(copy_), "<stdin>", scene);
}

}  // namespace particle::check
