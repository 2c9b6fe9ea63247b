#pragma once
// The program's output as psim check reads it: more than once where more than one reading is
// judged, since a reading set aside early is taken up again from the start if the others do worse
// (check.cpp). A file is opened again. Stdin cannot be read twice, so every byte read from it is
// also written to an unlinked temporary file (in TMPDIR, else /tmp): a later reader reads that
// copy, then goes on reading stdin where the copy ends. The copy holds what was read, no more
// (the reader's bounds hold: an endless program costs no more disk than reading it would).
#include <cstdint>
#include <memory>
#include <string>

#include "particle/output_text.hpp"
#include "particle/scene.hpp"

namespace particle::check {

class StdinCopy;

class OutputSource {
 public:
  // `path` "-" is stdin; `again`: whether it may be read more than once (else stdin is read as
  // it is, without a copy).
  OutputSource(std::string path, bool again);
  ~OutputSource();
  OutputSource(const OutputSource&) = delete;
  OutputSource& operator=(const OutputSource&) = delete;

  // A reader from the output's first line. Throws InputError where the output cannot be opened,
  // or stdin's copy cannot be made.
  std::unique_ptr<OutputReader> read(const Scene& scene);

 private:
  std::string path_;
  std::shared_ptr<StdinCopy> copy_;  // stdin, when read again; shared with each reader's stream
};

}  // namespace particle::check
