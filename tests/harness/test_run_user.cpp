// What ends with a confined run and what it cannot keep (issue 57): the runs' own user
// (run/run_user.hpp), whose processes are all killed; a folder killed when it holds too much
// (run/folder_limit.hpp); no memfd or SysV object in either tier (run/seccomp.hpp).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/shm.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run/folder_limit.hpp"
#include "run/run_user.hpp"
#include "run/runner.hpp"
#include "../scratch_folder.hpp"

using namespace psweep;
namespace fs = std::filesystem;

namespace {

// A process of `uid` that sleeps, started apart from every run (as a run left by a psweep killed
// outright would be): its pid; the caller reaps it.
pid_t sleeper_of(int uid) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (setresgid(uid, uid, uid) == 0 && setresuid(uid, uid, uid) == 0) pause();
    _exit(1);
  }
  return pid;
}

// How `pid` ended, waiting at most 5 s: the signal that killed it, or -1.
int killed_by(pid_t pid) {
  for (int i = 0; i < 500; ++i) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFSIGNALED(status) ? WTERMSIG(status) : -1;
    usleep(10000);
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return -1;
}

}  // namespace

TEST(RunUser, AsRootEveryRunIsAUserOfItsOwnWhoseProcessesAreKilledAfterIt) {
  if (geteuid() != 0) GTEST_SKIP() << "only root can change user";
  ChildIo io;
  run_as_own_user_if_root(io);
  ASSERT_TRUE(io.own_user);
  EXPECT_GE(io.uid, 65534 - kRunUsersCount);
  EXPECT_EQ(io.uid, io.gid);
  // The same user for every run of this process: it is its own for the process's life.
  ChildIo again;
  run_as_own_user_if_root(again);
  EXPECT_EQ(again.uid, io.uid);
  // A confined run says who it is; a process of its user outside it is gone afterwards.
  const pid_t stray = sleeper_of(io.uid);
  usleep(50000);
  io.confined = true;
  const ChildResult r = run_child({"/bin/sh", "-c", "id -u >&2"}, {"PATH=/usr/bin:/bin"}, 10,
                                  nullptr, io);
  EXPECT_EQ(r.stderr_tail, std::to_string(io.uid) + "\n");
  EXPECT_EQ(killed_by(stray), SIGKILL);
}

TEST(RunUser, ASysvSegmentLeftOfTheUserIsRemovedWhenItIsTaken) {
  if (geteuid() != 0) GTEST_SKIP() << "only root can change user";
  // One for each of the first users of the range: another test may hold the first.
  std::vector<int> segments;
  for (int uid = kRunUsersFirst; uid < kRunUsersFirst + 4; ++uid) {
    const int id = shmget(IPC_PRIVATE, 4096, IPC_CREAT | 0600);
    ASSERT_GE(id, 0);
    shmid_ds ds{};
    shmctl(id, IPC_STAT, &ds);
    ds.shm_perm.uid = static_cast<uid_t>(uid);
    ASSERT_EQ(shmctl(id, IPC_SET, &ds), 0);
    segments.push_back(id);
  }
  ChildIo io;
  run_as_own_user_if_root(io);
  ASSERT_TRUE(io.own_user);
  for (std::size_t i = 0; i < segments.size(); ++i) {
    shmid_ds ds{};
    const bool gone = shmctl(segments[i], IPC_STAT, &ds) != 0;
    EXPECT_EQ(gone, kRunUsersFirst + static_cast<int>(i) == io.uid) << "segment " << i;
    if (!gone) shmctl(segments[i], IPC_RMID, nullptr);
  }
}

TEST(RunUser, KillingAUsersProcessesSparesEveryOtherUser) {
  if (geteuid() != 0) GTEST_SKIP() << "only root can change user";
  ChildIo io;
  run_as_own_user_if_root(io);
  // Another user that no psweep takes: io.uid + 1 is the next run user, which a test running
  // beside this one may take, and taking a run user kills its processes (a flaky failure under
  // ctest -j2).
  const pid_t other = sleeper_of(kRunUsersFirst - 1);
  const pid_t mine = sleeper_of(io.uid);
  usleep(50000);
  kill_every_process_of(io.uid, io.gid);
  EXPECT_EQ(killed_by(mine), SIGKILL);
  EXPECT_EQ(waitpid(other, nullptr, WNOHANG), 0) << "another user's process was killed";
  kill(other, SIGKILL);
  waitpid(other, nullptr, 0);
}

TEST(FolderLimit, AFolderIsOverItsLimitInFilesInBytesOrInDepth) {
  const fs::path dir = test_support::scratch_folder("folder-limit") / "limit";
  fs::create_directories(dir);
  FolderLimit limit{dir.string(), 1 << 20, 10, "disk_mib = 1 MiB"};
  EXPECT_EQ(over_limit(limit), std::nullopt);
  for (int i = 0; i < 10; ++i) std::ofstream(dir / std::to_string(i)) << "x";
  EXPECT_EQ(over_limit(limit), std::nullopt);  // 10 files: at the limit, not over it
  std::ofstream(dir / "10") << "x";
  EXPECT_EQ(over_limit(limit), "its folder held more than 10 files (a file per 4 KiB of "
                               "disk_mib = 1 MiB): killed");
  limit.files = 1000;
  {
    std::ofstream big(dir / "big");
    big << std::string(2 << 20, 'y');  // written, not sparse: its blocks count
  }
  EXPECT_EQ(over_limit(limit), "its folder held more than disk_mib = 1 MiB: killed");
  fs::remove(dir / "big");
  fs::path deep = dir;
  for (int i = 0; i < 70; ++i) deep /= "d";
  fs::create_directories(deep);
  EXPECT_EQ(over_limit(limit), "its folder nested folders more than 64 deep: killed");
}

TEST(FolderLimit, ARunThatFillsItsFolderIsKilledAndSaysWhy) {
  const fs::path dir = test_support::scratch_folder("folder-run") / "run";
  fs::create_directories(dir);
  ChildIo io;
  io.folder = {dir.string(), 64 << 20, 500, "disk_mib = 64 MiB"};
  const ChildResult r = run_child(
      {"/bin/sh", "-c", "cd " + dir.string() + "; i=0; while :; do : > f$i; i=$((i+1)); done"},
      {"PATH=/usr/bin:/bin"}, 20, nullptr, io);
  EXPECT_EQ(r.outcome, Outcome::over_limit);
  EXPECT_EQ(r.over, "its folder held more than 500 files (a file per 4 KiB of disk_mib = 64 MiB): "
                    "killed");
  EXPECT_LT(r.process_s, 10);
}

TEST(SharedFilter, NoMemfdOrSysvObjectInAConfinedRun) {
  ChildIo io;
  io.confined = true;
  const ChildResult r = run_child(
      {"/usr/bin/python3", "-c",
       "import ctypes, os, sys\n"
       "libc = ctypes.CDLL(None, use_errno=True)\n"
       "try:\n    os.memfd_create('m'); print('memfd made', file=sys.stderr)\n"
       "except OSError as e:\n    print('memfd', e.errno, file=sys.stderr)\n"
       "print('shm', libc.shmget(0, 4096, 0o1600), ctypes.get_errno(), file=sys.stderr)\n"},
      {"PATH=/usr/bin:/bin"}, 20, nullptr, io);
  EXPECT_EQ(r.stderr_tail, "memfd 1\nshm -1 1\n");
}
