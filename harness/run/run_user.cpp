// The runs' user: see run_user.hpp.
#include "run/run_user.hpp"

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/msg.h>
#include <sys/sem.h>
#include <sys/shm.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace psweep {
namespace {

// Whether this process's user namespace maps every id of [first, first + count) (`map`:
// /proc/self/uid_map or gid_map, lines of "inside outside count").
bool mapped(const char* map, long first, long count) {
  std::ifstream in(map);
  for (long inside, outside, n; in >> inside >> outside >> n;)
    if (inside <= first && first + count <= inside + n) return true;
  return false;
}

// Where the locks live: a folder of root's alone, so that no user can hold a uid's lock.
std::string lock_folder() {
  for (const fs::path base : {fs::path("/run"), fs::temp_directory_path()}) {
    const fs::path dir = base / "psweep-run-users";
    mkdir(dir.c_str(), 0700);
    struct stat st {};
    if (lstat(dir.c_str(), &st) == 0 && S_ISDIR(st.st_mode) && st.st_uid == 0 &&
        (st.st_mode & 0077) == 0)
      return dir.string();
  }
  return {};
}

// The first uid of [first, first + count) that no account names and no other process holds,
// its lock kept open (close-on-exec) for this process's life; -1 when none is.
int take_uid(const std::string& folder, int first, int count) {
  if (!mapped("/proc/self/uid_map", first, count) || !mapped("/proc/self/gid_map", first, count))
    return -1;
  for (int uid = first; uid < first + count; ++uid) {
    if (getpwuid(static_cast<uid_t>(uid)) || getgrgid(static_cast<gid_t>(uid))) continue;
    const std::string path = folder + "/" + std::to_string(uid);
    const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0600);
    if (fd < 0) continue;
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) return uid;  // fd held: the lock with it
    close(fd);
  }
  return -1;
}

// Removes the SysV objects of `uid` listed in /proc/sysvipc/NAME, whose id is column 2 and owner
// column `uid_column` (1-based), with `remove` (shmctl, semctl or msgctl with IPC_RMID).
template <typename Remove>
void remove_ipc(const char* name, int uid_column, Remove remove, int uid) {
  std::ifstream in(std::string("/proc/sysvipc/") + name);
  std::string line;
  std::getline(in, line);  // the header
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<long> column;
    for (long value; column.size() < static_cast<std::size_t>(uid_column) && words >> value;)
      column.push_back(value);
    if (column.size() == static_cast<std::size_t>(uid_column) && column.back() == uid)
      remove(static_cast<int>(column[1]));
  }
}

struct RunUser {
  int uid = -1, gid = -1;
  bool own = false;
};

RunUser take_run_user() {
  RunUser user;
  if (const std::string folder = lock_folder(); !folder.empty()) {
    int uid = take_uid(folder, kRunUsersFirst, kRunUsersCount);
    if (uid < 0) uid = take_uid(folder, 65534 - kRunUsersCount, kRunUsersCount);
    if (uid >= 0) {
      user = {uid, uid, true};
      // What an earlier holder, killed outright, or an older psweep, which let runs make SysV
      // objects, left of it. Runs can make no SysV object now (run/seccomp.hpp).
      kill_every_process_of(uid, uid);
      remove_ipc("shm", 8, [](int id) { shmctl(id, IPC_RMID, nullptr); }, uid);
      remove_ipc("sem", 5, [](int id) { semctl(id, 0, IPC_RMID); }, uid);
      remove_ipc("msg", 8, [](int id) { msgctl(id, IPC_RMID, nullptr); }, uid);
      return user;
    }
  }
  const passwd* nobody = getpwnam("nobody");
  user.uid = nobody ? static_cast<int>(nobody->pw_uid) : 65534;
  user.gid = nobody ? static_cast<int>(nobody->pw_gid) : 65534;
  return user;
}

}  // namespace

void run_as_own_user_if_root(ChildIo& io) {
  if (geteuid() != 0) return;
  static const RunUser user = take_run_user();
  io.uid = user.uid;
  io.gid = user.gid;
  io.own_user = user.own;
}

void kill_every_process_of(int uid, int gid) {
  if (uid <= 0) return;
  const pid_t killer = fork();
  if (killer == 0) {
    // kill(-1) reaches every process whose real or saved uid is ours, but not the caller. Once
    // is enough: the kernel signals them all under the lock that fork takes to add a child, and
    // a fork that meets the pending SIGKILL fails, so no process of the user is born after it.
    // (Its result says nothing: other users' processes, refused, count as reached.)
    if (setgroups(0, nullptr) != 0 || setresgid(gid, gid, gid) != 0 ||
        setresuid(uid, uid, uid) != 0)
      _exit(1);
    kill(-1, SIGKILL);
    _exit(0);
  }
  if (killer < 0) return;
  while (waitpid(killer, nullptr, 0) < 0 && errno == EINTR) {
  }
}

}  // namespace psweep
