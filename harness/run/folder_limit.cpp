// A folder with a size: see folder_limit.hpp.
#include "run/folder_limit.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace psweep {
namespace {

// Deeper than this, a walk would hold a descriptor per level: a run that nests so deep is over.
constexpr int kMaxDepth = 64;

struct Usage {
  std::uint64_t bytes = 0, files = 0;
  bool too_deep = false;
};

// Adds the entries under the open folder `dir` (closed here) to `usage`, stopping once over.
void walk(int dir, int depth, const FolderLimit& limit, Usage& usage) {
  DIR* d = fdopendir(dir);
  if (!d) {
    close(dir);
    return;
  }
  while (const dirent* e = readdir(d)) {
    if (std::strcmp(e->d_name, ".") == 0 || std::strcmp(e->d_name, "..") == 0) continue;
    struct stat st {};
    if (fstatat(dirfd(d), e->d_name, &st, AT_SYMLINK_NOFOLLOW) != 0) continue;  // gone since
    ++usage.files;
    usage.bytes += static_cast<std::uint64_t>(st.st_blocks) * 512;
    if (usage.files > limit.files || usage.bytes > limit.bytes) break;
    if (!S_ISDIR(st.st_mode)) continue;
    if (depth >= kMaxDepth) {
      usage.too_deep = true;
      break;
    }
    const int sub = openat(dirfd(d), e->d_name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (sub >= 0) walk(sub, depth + 1, limit, usage);
    if (usage.too_deep || usage.files > limit.files || usage.bytes > limit.bytes) break;
  }
  closedir(d);
}

}  // namespace

std::optional<std::string> over_limit(const FolderLimit& limit) {
  if (limit.path.empty()) return std::nullopt;
  const int dir = open(limit.path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return std::nullopt;
  Usage usage;
  walk(dir, 0, limit, usage);
  if (usage.too_deep)
    return fmt::format("its folder nested folders more than {} deep: killed", kMaxDepth);
  if (usage.bytes > limit.bytes)
    return fmt::format("its folder held more than {}: killed", limit.name);
  if (usage.files > limit.files)
    return fmt::format("its folder held more than {} files (a file per 4 KiB of {}): killed",
                       limit.files, limit.name);
  return std::nullopt;
}

}  // namespace psweep
