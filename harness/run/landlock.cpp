// Landlock: see landlock.hpp. The UAPI written out here: Debian 12's headers stop at ABI 2, and
// the net and scope fields are what make the ruleset worth having.
#include "run/landlock.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cstdint>

namespace psweep {
namespace {

constexpr long kCreateRuleset = 444, kAddRule = 445, kRestrictSelf = 446;
constexpr std::uint32_t kVersion = 1;  // LANDLOCK_CREATE_RULESET_VERSION
constexpr int kPathBeneath = 1;        // LANDLOCK_RULE_PATH_BENEATH

struct RulesetAttr {
  std::uint64_t handled_access_fs, handled_access_net, scoped;
};

struct [[gnu::packed]] PathBeneathAttr {
  std::uint64_t allowed_access;
  std::int32_t parent_fd;
};

constexpr std::uint64_t kExecute = 1 << 0, kWriteFile = 1 << 1, kReadFile = 1 << 2,
                        kReadDir = 1 << 3, kTruncate = 1 << 14, kIoctlDev = 1 << 15;

// Every file-system right the ABI knows: ABI 1 the first 13, 2 REFER, 3 TRUNCATE, 5 IOCTL_DEV.
std::uint64_t fs_rights(int abi) {
  std::uint64_t rights = (1ULL << 13) - 1;
  if (abi >= 2) rights |= 1ULL << 13;
  if (abi >= 3) rights |= kTruncate;
  if (abi >= 5) rights |= kIoctlDev;
  return rights;
}

// A rule for `fd`'s path; a file takes only the rights of files (the kernel refuses others).
bool add_rule(int ruleset, int fd, std::uint64_t rights) {
  struct stat st {};
  if (fstat(fd, &st) != 0) return false;
  if (!S_ISDIR(st.st_mode)) rights &= kExecute | kWriteFile | kReadFile | kTruncate | kIoctlDev;
  const PathBeneathAttr rule{rights, fd};
  return syscall(kAddRule, ruleset, kPathBeneath, &rule, 0) == 0;
}

}  // namespace

int landlock_abi() {
  const long abi = syscall(kCreateRuleset, nullptr, 0, kVersion);
  return abi > 0 ? static_cast<int>(abi) : 0;
}

PathRules::PathRules(const std::vector<std::string>& read, const std::vector<std::string>& dev,
                     const std::vector<std::string>& write) {
  const auto open_all = [](const std::vector<std::string>& paths, std::vector<int>& fds) {
    for (const std::string& path : paths)
      if (const int fd = open(path.c_str(), O_PATH | O_CLOEXEC); fd >= 0) fds.push_back(fd);
  };
  open_all(read, readable);
  open_all(dev, devices);
  open_all(write, writable);
}

PathRules::~PathRules() {
  for (const auto* fds : {&readable, &devices, &writable})
    for (int fd : *fds) close(fd);
}

bool restrict_to(const PathRules& rules, int abi) {
  const std::uint64_t all = fs_rights(abi);
  RulesetAttr attr{all, 0, 0};
  std::size_t size = sizeof attr.handled_access_fs;
  if (abi >= 4) {  // TCP bind and connect: handled, and no rule allows them
    attr.handled_access_net = 3;
    size = 2 * sizeof(std::uint64_t);
  }
  if (abi >= 6) {  // abstract UNIX sockets and signals outside the domain
    attr.scoped = 3;
    size = sizeof attr;
  }
  const int ruleset = static_cast<int>(syscall(kCreateRuleset, &attr, size, 0));
  if (ruleset < 0) return false;
  const std::uint64_t read = kExecute | kReadFile | kReadDir;
  const std::uint64_t file =
      kReadFile | kWriteFile | (abi >= 3 ? kTruncate : 0) | (abi >= 5 ? kIoctlDev : 0);
  bool ok = true;
  for (int fd : rules.readable) ok = ok && add_rule(ruleset, fd, read);
  for (int fd : rules.devices) ok = ok && add_rule(ruleset, fd, file);
  for (int fd : rules.writable) ok = ok && add_rule(ruleset, fd, all);
  ok = ok && prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 && syscall(kRestrictSelf, ruleset, 0) == 0;
  close(ruleset);
  return ok;
}

}  // namespace psweep
