#pragma once
// Where a file the lab writes at a path someone named goes, and how (psim's --metrics and
// --state-at, psweep's results files). A regular file, or none yet, is written whole or not at all:
// a temporary beside it renamed over it. Anything else is someone's stream (/dev/null, a FIFO,
// /dev/stdout): renaming over it would replace the device or pipe itself for every other program,
// so it is written in place. A symbolic link names where to write; renaming over the link would
// cut it, so its final target is written instead.
#include <sys/types.h>

#include <optional>
#include <string>

namespace particle {

struct FileId {
  dev_t device = 0;
  ino_t inode = 0;
  bool operator==(const FileId&) const = default;
};

// What is at `path` now, following links; nullopt when nothing is (or it cannot be seen).
std::optional<FileId> file_id(const std::string& path);

struct OutputTarget {
  enum class Kind { absent, regular, stream, unusable };
  Kind kind = Kind::absent;
  std::string path;      // where to write: the final target of a chain of links, else as given
  std::string resolved;  // `path` absolute with its folders' links resolved: one name per file
  std::optional<FileId> id;
  std::string problem;  // when unusable: "is a directory", "cannot be looked at (why)"

  // Through a temporary and rename(), or in place.
  bool atomic() const { return kind == Kind::absent || kind == Kind::regular; }
  // One file written twice: the same inode, or nothing there yet under the same resolved name.
  bool same_file(const OutputTarget& other) const;
};

OutputTarget output_target(const std::string& path);

}  // namespace particle
