#pragma once
// A file that appears whole or not at all: written under a temporary name next to it and renamed
// over its path by commit(), so whoever reads it (psweep, a script) never finds half of it, even
// when psim is interrupted or fails midway. Not committed, the temporary is removed and a file
// already at the path is left as it was. The temporary exists only from the first get() on (the
// metrics: only while they are written), so a psim killed outright (psweep's timeout) leaves
// nothing behind either. A device, FIFO or /dev/stdout is written in place and a link's target
// is written instead of the link (particle/output_path.hpp).
#include <cstdio>
#include <string>
#include <string_view>

#include "particle/output_path.hpp"

namespace lab {

class WholeFile {
 public:
  // Checks up front that the path can be written (a directory cannot; for a file, that the
  // temporary PATH.tmp-PID can be created, and removes it again), so a bad path is an error
  // before the run; particle::InputError naming `option` (when not empty) when it cannot.
  WholeFile(std::string path, std::string_view option);
  ~WholeFile();
  WholeFile(const WholeFile&) = delete;
  WholeFile& operator=(const WholeFile&) = delete;

  // The temporary (in place: the file itself), opened on the first call.
  std::FILE* get();
  // Closes the temporary and renames it to the path; InputError when writing failed.
  void commit();

  const particle::OutputTarget& target() const { return target_; }
  const std::string& path() const { return path_; }
  const std::string& option() const { return option_; }

 private:
  [[noreturn]] void fail(int error) const;
  std::string prefix() const;  // "OPTION: ", or nothing
  void discard();

  std::string path_, option_;
  particle::OutputTarget target_;
  std::string temp_;  // target_.path itself when written in place
  std::FILE* file_ = nullptr;
};

}  // namespace lab
