// A folder with a size where no file system gives it one: the contained tier's run folder
// (run/contain.hpp) is a plain folder of the host's /tmp, whose RLIMIT_FSIZE bounds each file and
// not how many (a run once wrote 121,989 files in 6 s, issue 57). psweep walks it every
// kPollMs while the run lives and kills the run the first time it holds more than its bytes or
// files: what one poll interval lets a program write past them is the overshoot, said in
// docs/faults.md.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace psweep {

struct FolderLimit {
  std::string path;         // empty: none
  std::uint64_t bytes = 0;  // disk used (allocated blocks: a sparse file counts what it holds)
  std::uint64_t files = 0;  // entries of every kind, folders included
  std::string name;         // the limit as the config names it, for the message
};

constexpr int kFolderPollMs = 100;

// Why the folder is over its limit ("its folder held more than disk_mib = 256 MiB"), or nothing.
// A folder nested past what the walk follows counts as over it: what it cannot count is not left.
std::optional<std::string> over_limit(const FolderLimit& limit);

}  // namespace psweep
