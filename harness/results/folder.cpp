// The results folder: see folder.hpp.
#include "results/folder.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "results/results.hpp"

namespace fs = std::filesystem;

namespace psweep {
namespace {

constexpr const char* result_files[] = {"runs.csv", "summary.csv", "meta.json"};

// A result file or an input is written whole to NAME.tmp-PID and renamed (lab::WholeFile, psim's
// own outputs alike): a psweep killed (kill -9), and its psim with it, between the two leaves the
// temporary. Whoever holds the lock is the folder's only writer, so every such temporary of a
// result file, and every one in inputs/ (psweep's alone), is a dead sweep's.
void remove_dead_writers_temporaries(const fs::path& folder) {
  const auto remove_if = [](const fs::path& dir, auto&& dead) {
    std::error_code error;  // no inputs/ yet: nothing to remove
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, error))
      if (dead(entry.path().filename().string())) {
        std::error_code ignored;  // gone already, or not ours to remove: the sweep goes on
        fs::remove(entry.path(), ignored);
      }
  };
  remove_if(folder, [](const std::string& name) {
    for (const char* file : result_files)
      if (name.rfind(std::string(file) + ".tmp-", 0) == 0) return true;
    return false;
  });
  remove_if(folder / "inputs",
            [](const std::string& name) { return name.find(".tmp-") != std::string::npos; });
}

}  // namespace

FolderLock::FolderLock(const fs::path& folder) {
  fs::create_directories(folder);
  const fs::path path = folder / ".psweep.lock";
  // Close-on-exec: a psim child must not keep the folder locked after psweep is gone.
  fd_ = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error(
        fmt::format("cannot open {}: {}", path.string(), std::strerror(errno)));
  if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    close(fd_);
    if (error != EWOULDBLOCK)
      throw std::runtime_error(
          fmt::format("cannot lock {}: {}", path.string(), std::strerror(error)));
    std::string holder = read_file(path.string());
    holder = holder.substr(0, holder.find('\n'));
    throw FolderBusy(fmt::format(
        "{} is in use by another psweep (PID {}, lock {}); wait until it ends (while kill -0 {} "
        "2>/dev/null; do sleep 10; done) or choose another folder",
        folder.string(), holder.empty() ? "unknown" : holder, path.string(),
        holder.empty() ? "PID" : holder));
  }
  const std::string pid = fmt::format("{}\n", getpid());
  if (ftruncate(fd_, 0) != 0 || write(fd_, pid.data(), pid.size()) < 0)
    std::fprintf(stderr, "psweep: warning: cannot record the PID in %s: %s\n", path.c_str(),
                 std::strerror(errno));
  remove_dead_writers_temporaries(folder);
}

FolderLock::~FolderLock() { close(fd_); }

bool holds_results(const fs::path& out) {
  for (const char* name : result_files)
    if (fs::exists(fs::symlink_status(out / name))) return true;
  return false;
}

void set_aside_previous(const fs::path& out) {
  if (!holds_results(out)) return;
  fs::path previous = out / "previous";
  for (int n = 2; fs::exists(fs::symlink_status(previous)); ++n)
    previous = out / fmt::format("previous-{}", n);
  fs::create_directories(previous);
  for (const char* name : result_files)
    if (fs::exists(fs::symlink_status(out / name))) fs::rename(out / name, previous / name);
  std::fprintf(stderr,
               "psweep: moved the earlier results in %s to %s (use --resume to continue a sweep)\n",
               out.c_str(), previous.c_str());
}

}  // namespace psweep
