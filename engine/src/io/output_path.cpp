#include "particle/output_path.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace particle {
namespace fs = std::filesystem;

namespace {

// The kernel's own bound on links followed in one lookup (ELOOP beyond).
constexpr int kMaxLinks = 40;

bool is_link(const fs::path& path) {
  struct stat st {};
  return lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode);
}

fs::path resolved_name(const fs::path& path) {
  std::error_code ec;
  const fs::path folder = fs::weakly_canonical(fs::absolute(path, ec).parent_path(), ec);
  return ec ? path : folder / path.filename();
}

}  // namespace

std::optional<FileId> file_id(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return std::nullopt;
  return FileId{st.st_dev, st.st_ino};
}

bool OutputTarget::same_file(const OutputTarget& other) const {
  return id ? id == other.id : !other.id && resolved == other.resolved;
}

OutputTarget output_target(const std::string& given) {
  OutputTarget t;
  fs::path path = given;
  for (int links = 0; links < kMaxLinks && is_link(path); ++links) {
    // A descriptor's link (/dev/stdout -> /proc/self/fd/1) names an open file, often a pipe
    // with no path at all: only opening the link itself reaches it.
    if (resolved_name(path).string().rfind("/proc/", 0) == 0) break;
    std::error_code ec;
    const fs::path target = fs::read_symlink(path, ec);
    if (ec) break;
    path = target.is_absolute() ? target : path.parent_path() / target;
  }
  t.path = path.string();
  t.resolved = resolved_name(path).string();
  struct stat st {};
  if (stat(given.c_str(), &st) != 0) {
    if (errno != ENOENT) {
      t.kind = OutputTarget::Kind::unusable;
      t.problem = std::string("cannot be looked at (") + std::strerror(errno) + ")";
    }
    return t;
  }
  t.id = FileId{st.st_dev, st.st_ino};
  if (S_ISDIR(st.st_mode)) {
    t.kind = OutputTarget::Kind::unusable;
    t.problem = "is a directory";
  } else if (S_ISREG(st.st_mode) && !is_link(path)) {
    t.kind = OutputTarget::Kind::regular;
  } else {
    t.kind = OutputTarget::Kind::stream;
    t.path = given;
  }
  return t;
}

}  // namespace particle
