#pragma once
// A file that appears whole or not at all: written under a temporary name next to it and renamed
// over its path by commit(), so whoever reads it (psweep, a script) never finds half of it, even
// when psim is interrupted or fails midway. Not committed, the temporary is removed and a file
// already at the path is left as it was. The temporary exists only from the first get() on (the
// metrics: only while they are written), so a psim killed outright (psweep's timeout) leaves
// nothing behind either.
#include <cstdio>
#include <string>
#include <string_view>

namespace psim {

class WholeFile {
 public:
  // Checks up front that the temporary PATH.tmp-PID can be created (and removes it again), so a
  // bad path is an error before the run; particle::InputError naming `option` when it cannot.
  WholeFile(std::string path, std::string_view option);
  ~WholeFile();
  WholeFile(const WholeFile&) = delete;
  WholeFile& operator=(const WholeFile&) = delete;

  // The temporary, created on the first call.
  std::FILE* get();
  // Closes the temporary and renames it to the path; InputError when writing failed.
  void commit();

 private:
  [[noreturn]] void fail(int error) const;

  std::string path_, temp_, option_;
  std::FILE* file_ = nullptr;
};

}  // namespace psim
