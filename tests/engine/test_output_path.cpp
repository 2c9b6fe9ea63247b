// Where psim and psweep write a file someone named (particle/output_path.hpp): a regular file or
// none through a temporary, a link's final target instead of the link, a FIFO and a descriptor
// (/dev/stdout) in place, a directory refused; one file under two names is one file.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "particle/output_path.hpp"

namespace fs = std::filesystem;
using particle::output_target;
using Kind = particle::OutputTarget::Kind;

namespace {

fs::path folder() {
  const fs::path dir = fs::path(::testing::TempDir()) /
                       (std::string("output_path_") +
                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST(OutputPath, FilesAreWrittenWholeAndOthersInPlace) {
  const fs::path dir = folder();
  EXPECT_EQ(output_target((dir / "new").string()).kind, Kind::absent);
  std::ofstream(dir / "file") << "x";
  EXPECT_EQ(output_target((dir / "file").string()).kind, Kind::regular);
  ASSERT_EQ(mkfifo((dir / "fifo").c_str(), 0600), 0);
  const auto fifo = output_target((dir / "fifo").string());
  EXPECT_EQ(fifo.kind, Kind::stream);
  EXPECT_FALSE(fifo.atomic());
  // A descriptor's link may name a pipe with no path: written through the link itself.
  const auto out = output_target("/dev/stdout");
  EXPECT_TRUE(out.kind == Kind::stream) << out.path;
  EXPECT_EQ(out.path, "/dev/stdout");
  const auto d = output_target(dir.string());
  EXPECT_EQ(d.kind, Kind::unusable);
  EXPECT_EQ(d.problem, "is a directory");
}

TEST(OutputPath, LinksAreFollowedToTheirFinalTarget) {
  const fs::path dir = folder();
  std::ofstream(dir / "file") << "x";
  fs::create_symlink("file", dir / "one");
  fs::create_symlink(dir / "one", dir / "two");
  const auto two = output_target((dir / "two").string());
  EXPECT_EQ(two.kind, Kind::regular);
  EXPECT_EQ(fs::path(two.path), dir / "file");
  fs::create_symlink("missing", dir / "dangling");
  const auto dangling = output_target((dir / "dangling").string());
  EXPECT_EQ(dangling.kind, Kind::absent);
  EXPECT_EQ(fs::path(dangling.path), dir / "missing");
  fs::create_symlink("loop", dir / "loop");
  EXPECT_EQ(output_target((dir / "loop").string()).kind, Kind::unusable);
}

TEST(OutputPath, OneFileUnderTwoNamesIsOneFile) {
  const fs::path dir = folder();
  std::ofstream(dir / "file") << "x";
  fs::create_symlink("file", dir / "link");
  EXPECT_TRUE(output_target((dir / "link").string())
                  .same_file(output_target((dir / "." / "file").string())));
  fs::create_symlink("absent", dir / "to_absent");
  EXPECT_TRUE(output_target((dir / "to_absent").string())
                  .same_file(output_target((dir / "absent").string())));
  EXPECT_FALSE(output_target((dir / "absent").string())
                   .same_file(output_target((dir / "other").string())));
  EXPECT_FALSE(output_target((dir / "absent").string())
                   .same_file(output_target((dir / "file").string())));
}
