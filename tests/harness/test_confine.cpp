// Confinement (run/confine.hpp): the sandbox's arguments and environment, the limits and env of a
// config, and what is said of a program that cannot be executed. The sandbox itself, against
// hostile programs, is tested end to end in tests/python/test_confinement.py.
#include <elf.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "config/program.hpp"
#include "run/confine.hpp"

using namespace psweep;
namespace fs = std::filesystem;

namespace {

// Whether `words` holds `seq` as consecutive words.
bool has(const std::vector<std::string>& words, const std::vector<std::string>& seq) {
  return std::search(words.begin(), words.end(), seq.begin(), seq.end()) != words.end();
}

Config with_programs(const std::string& programs, const std::string& limits = "") {
  return parse_config(
      R"({"name": "p", "base": {"engine": "mine", "N": 10, "L": 100, "r": 1, "S": 3},)" +
          (limits.empty() ? "" : R"("limits": )" + limits + ",") + R"("programs": )" + programs +
          "}",
      "p.json");
}

std::string error_of(const std::string& programs, const std::string& limits = "") {
  try {
    with_programs(programs, limits);
  } catch (const ConfigError& e) {
    return std::string(e.what()).substr(std::string("p.json: ").size());
  }
  return "(no error)";
}

class TempFolder {
 public:
  TempFolder() {
    std::string pattern = (fs::temp_directory_path() / "confine-test-XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempFolder() { fs::remove_all(path_); }
  std::string file(const std::string& name, const std::string& text, fs::perms perms) const {
    const std::string p = (path_ / name).string();
    std::ofstream(p) << text;
    fs::permissions(p, perms);
    return p;
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

constexpr auto kExecutable = fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read;

}  // namespace

TEST(Confine, TheSandboxIsolatesEverythingAndLimitsTheRun) {
  SandboxSpec spec;
  spec.bwrap = "/usr/bin/bwrap";
  spec.prlimit = "/usr/bin/prlimit";
  spec.limits.memory_mib = 2048;
  spec.limits.processes = 64;
  spec.limits.open_files = 128;
  spec.limits.disk_mib = 32;
  spec.cpu_s = 19.5;
  spec.file_bytes = 1000;
  spec.threads = 2;
  spec.files = {{"/tmp/stage/0/mine", "/program/mine"}};
  spec.hide = {"/usr/src/lab", "/work/lab"};
  spec.env = {"OMP_NUM_THREADS=2"};
  const Confined c = sandbox_command(spec, {"/program/mine", "2"});
  const auto& a = c.argv;
  EXPECT_EQ(a.front(), "/usr/bin/bwrap");
  // every namespace (user, PID, network, IPC, UTS, cgroup); the tree dies with psweep
  EXPECT_TRUE(has(a, {"--unshare-all", "--die-with-parent", "--new-session"}));
  EXPECT_TRUE(has(a, {"--ro-bind", "/usr", "/usr"}));
  EXPECT_TRUE(has(a, {"--ro-bind", "/etc", "/etc"}));
  // a repository under /usr is hidden; one elsewhere is simply not there
  EXPECT_TRUE(has(a, {"--tmpfs", "/usr/src/lab"}));
  EXPECT_FALSE(has(a, {"--tmpfs", "/work/lab"}));
  // /dev read-only; the writable folders mounted inside, sized in bytes and in files, by the
  // sandbox's root, which then drops every capability for good
  EXPECT_TRUE(has(a, {"--dev", "/dev", "--remount-ro", "/dev", "--dir", "/tmp", "--dir", "/box"}));
  EXPECT_TRUE(has(a, {"--ro-bind", "/tmp/stage/0/mine", "/program/mine", "--remount-ro", "/"}));
  EXPECT_TRUE(has(a, {"--uid", "0", "--gid", "0", "--cap-add", "CAP_SYS_ADMIN", "--cap-add",
                      "CAP_SETPCAP", "--chdir", "/", "--", "/bin/sh", "-c"}));
  const std::string script = *(std::find(a.begin(), a.end(), "-c") + 1);
  EXPECT_NE(script.find("for d in /tmp /dev/shm /box; do mount -t tmpfs -o "
                        "size=33554432,nr_inodes=8192,mode=1777 tmpfs $d; done; cd /box"),
            std::string::npos)
      << script;
  EXPECT_NE(script.find("exec setpriv --inh-caps=-all --ambient-caps=-all --bounding-set=-all"),
            std::string::npos);
  EXPECT_TRUE(has(a, {"sandbox", "/usr/bin/prlimit", "--cpu=20:21", "--data=2147483648",
                      // the address space: memory, 512 MiB for libraries, 128 MiB per thread
                      "--as=2952790016", "--stack=8388608:8388608", "--nproc=64", "--nofile=128",
                      "--core=0", "--fsize=1000", "--", "/program/mine", "2"}));
  EXPECT_EQ(std::count(a.begin(), a.end(), "--bind"), 0);  // nothing of the host writable
  EXPECT_EQ(c.env, (std::vector<std::string>{"PATH=/usr/local/bin:/usr/bin:/bin", "HOME=/box",
                                             "OMP_NUM_THREADS=2"}));
}

TEST(Confine, TheProgramAndTheFilesItNamesAreStagedAndMapped) {
  TempFolder t;
  const std::string prog = t.file("mine", "#!/bin/sh\n", kExecutable);
  const std::string data = t.file("table.txt", "1 2 3\n", fs::perms::owner_read);
  Program p;
  p.facts.name = "mine";
  Stage stage;
  const Confined c =
      confine(p, {prog, data, "7", "/bin/sh"}, {"OMP_NUM_THREADS=1"}, 10, 2, 0, {}, stage);
  const auto dashes = std::find(c.argv.rbegin(), c.argv.rend(), "--").base();
  const std::vector<std::string> inside(dashes, c.argv.end());
  EXPECT_EQ(inside,
            (std::vector<std::string>{"/program/mine", "/program/1/table.txt", "7", "/bin/sh"}));
  EXPECT_TRUE(has(c.argv, {"--cpu=20:21"}));  // the default: timeout_s x the run's CPUs
  // the copies: readable by the run's user, writable by no one, executable as the original was
  const auto staged = std::find(c.argv.begin(), c.argv.end(), "/program/mine") - 1;
  EXPECT_NE(*staged, prog);
  const auto perms = fs::status(*staged).permissions();
  EXPECT_EQ(perms & (fs::perms::owner_write | fs::perms::others_write), fs::perms::none);
  EXPECT_NE(perms & fs::perms::others_exec, fs::perms::none);
  const auto table = std::find(c.argv.begin(), c.argv.end(), "/program/1/table.txt") - 1;
  EXPECT_EQ(fs::status(*table).permissions() & fs::perms::others_exec, fs::perms::none);
  // a program replaced during the sweep: the first copy is what runs
  t.file("mine", "#!/bin/sh\necho changed\n", kExecutable);
  EXPECT_EQ(stage.add(prog), *staged);
}

TEST(Confine, LimitsAndEnvFromTheConfigAndEachProgram) {
  const Config c = with_programs(
      R"({"a": {"command": ["./a"]},
          "b": {"command": ["./b"], "limits": {"memory_mib": 64}, "env": {"B_MODE": "fast"}}})",
      R"({"memory_mib": 512, "processes": 32, "cpu_s": 5})");
  EXPECT_EQ(c.program("a")->limits.memory_mib, 512);
  EXPECT_EQ(c.program("a")->limits.processes, 32);
  EXPECT_EQ(c.program("b")->limits.memory_mib, 64);
  EXPECT_EQ(c.program("b")->limits.processes, 32);  // the config's, where its own say nothing
  EXPECT_EQ(c.program("b")->limits.cpu_s, 5);
  EXPECT_EQ(c.program("b")->env,
            (std::vector<std::pair<std::string, std::string>>{{"B_MODE", "fast"}}));
  const Config d = with_programs(R"({"a": {"command": ["./a"]}})");
  EXPECT_EQ(d.program("a")->limits.memory_mib, 2048);
  EXPECT_EQ(d.program("a")->limits.cpu_s, 0);
}

TEST(Confine, LimitAndEnvErrorsNameTheirKey) {
  const std::string a = R"({"a": {"command": ["./a"]}})";
  EXPECT_EQ(error_of(a, R"({"memory": 5})"),
            "limits.memory: unknown key (expected one of cpu_s, memory_mib, processes, "
            "open_files, disk_mib)");
  EXPECT_EQ(error_of(a, R"({"processes": 0})"),
            "limits.processes: expected a positive integer, got 0");
  EXPECT_EQ(error_of(a, R"({"processes": 2})"), "limits.processes: expected at least 4");
  EXPECT_EQ(error_of(a, R"([])"),
            "limits: expected an object of cpu_s, memory_mib, processes, open_files, disk_mib");
  EXPECT_EQ(error_of(R"({"a": {"command": ["./a"], "limits": {"cpu_s": -1}}})"),
            "programs.a.limits.cpu_s: expected a positive number, got -1");
  EXPECT_EQ(error_of(R"({"a": {"command": ["./a"], "env": {"HOME": "/x"}}})"),
            "programs.a.env.HOME: set by psweep (PATH, HOME and OMP_* are the run's own)");
  EXPECT_EQ(error_of(R"({"a": {"command": ["./a"], "env": {"1X": "y"}}})"),
            "programs.a.env.1X: expected a variable name of letters, digits and '_'");
  EXPECT_EQ(error_of(R"({"a": {"command": ["./a"], "env": {"X": 1}}})"),
            "programs.a.env.X: expected a string, got 1");
}

TEST(Confine, WhyAProgramCannotBeExecuted) {
  TempFolder t;
  EXPECT_EQ(cannot_execute((t.path() / "none").string()), "No such file or directory");
  EXPECT_EQ(cannot_execute("no-such-program-on-path"), "not found on PATH");
  EXPECT_EQ(cannot_execute(t.path().string()), "Is a directory");
  EXPECT_EQ(cannot_execute(t.file("plain", "#!/bin/sh\n", fs::perms::owner_read)),
            "Permission denied (not executable: chmod +x it)");
  EXPECT_EQ(cannot_execute(t.file("lost", "#!/usr/bin/no-such-shell -e\n", kExecutable)),
            "its interpreter /usr/bin/no-such-shell (the #! line) does not exist");
  EXPECT_EQ(cannot_execute(t.file("blank", "#!   \n", kExecutable)),
            "its #! line names no interpreter");
  EXPECT_EQ(cannot_execute(t.file("ok", "#!/bin/sh\nexit 0\n", kExecutable)), std::nullopt);
  EXPECT_EQ(cannot_execute(t.file("cut",
                                  "\x7f"
                                  "ELF",
                                  kExecutable)),
            "an ELF file cut short (fewer than 20 bytes): not a program");
  EXPECT_EQ(cannot_execute(t.file("crlf", "#!/bin/sh\r\nexit 0\r\n", kExecutable)),
            "its #! line ends in a carriage return (Windows line endings, CR LF), so the system "
            "looks for an interpreter whose name ends in \\r: convert the file with dos2unix");
  EXPECT_EQ(cannot_execute(t.file("bare", "echo 0 0 1 1 0 0\n", kExecutable)),
            "neither a program (ELF) nor a script with a #! line: add one, such as #!/bin/sh");
  // This test's own program runs here; the same bytes marked for another machine, or as an
  // object file, do not.
  std::ifstream self("/proc/self/exe", std::ios::binary);
  std::string elf((std::istreambuf_iterator<char>(self)), std::istreambuf_iterator<char>());
  EXPECT_EQ(cannot_execute(t.file("native", elf, kExecutable)), std::nullopt);
  elf[18] = static_cast<char>(EM_AARCH64);
  elf[19] = 0;
  EXPECT_EQ(cannot_execute(t.file("arm", elf, kExecutable)),
            "a program for AArch64 (arm64), and this machine is x86-64: build it here");
  std::ifstream again("/proc/self/exe", std::ios::binary);
  std::string object((std::istreambuf_iterator<char>(again)), std::istreambuf_iterator<char>());
  object[16] = ET_REL;
  EXPECT_EQ(cannot_execute(t.file("object", object, kExecutable)),
            "an ELF object file, not a linked program: link it (g++ -o NAME ...)");
}
