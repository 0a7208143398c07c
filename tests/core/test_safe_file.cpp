// core/safe_file.hpp: what is renamed into place is flushed first (sync_file), never through a link, and
// write_file_atomically leaves the whole content or the previous file; a FolderLock waits out holders.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <string>
#include <thread>

#include "core/safe_file.hpp"

namespace hfbake {
namespace {
namespace fs = std::filesystem;

class SafeFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hfbake_safe_file_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(SafeFile, SyncFileFlushesAFileAndNeverFollowsALink) {
  std::ofstream(dir_ / "a") << "bytes";
  EXPECT_EQ(sync_file(dir_ / "a"), 0);
  EXPECT_EQ(sync_file(dir_ / "missing"), ENOENT);
  fs::create_symlink(dir_ / "a", dir_ / "link");
  EXPECT_EQ(sync_file(dir_ / "link"), ELOOP);  // O_NOFOLLOW: a planted link is not what was staged
  sync_folder(dir_);                           // no error to report: the rename stands either way
  sync_folder(dir_ / "missing");
}

// A file a command line names: its missing folders are no problem (write_named_output makes them); a path
// under a file or a dangling link is, naming it; a stream is written through whatever its folder.
TEST_F(SafeFile, NamedOutputsMakeTheirFoldersAndRefuseAPathUnderAFile) {
  const fs::path deep = dir_ / "a" / "b" / "s.json";
  EXPECT_EQ(named_output_problem(deep), "");
  write_named_output(deep, "{}\n");
  std::ifstream in(deep);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "{}\n");
  std::ofstream(dir_ / "file") << "x";
  EXPECT_EQ(named_output_problem(dir_ / "file" / "c" / "s.json"),
            (dir_ / "file").string() + " is not a folder");
  fs::create_symlink(dir_ / "nowhere", dir_ / "dangling");
  EXPECT_EQ(named_output_problem(dir_ / "dangling" / "s.json"),
            (dir_ / "dangling").string() + " is not a folder");
  ASSERT_EQ(mkfifo((dir_ / "locked_fifo").c_str(), 0600), 0);
  fs::create_directory(dir_ / "locked");
  fs::create_symlink(dir_ / "locked_fifo", dir_ / "locked" / "out");
  fs::permissions(dir_ / "locked", fs::perms::owner_read | fs::perms::owner_exec);
  EXPECT_EQ(named_output_problem(dir_ / "locked" / "out"), "");  // a link to a FIFO: written through
  if (geteuid() != 0) {                                          // root writes into any folder
    EXPECT_EQ(named_output_problem(dir_ / "locked" / "s.json").rfind("cannot write into ", 0), 0u);
  }
  fs::permissions(dir_ / "locked", fs::perms::owner_all);
}

// A descriptor of the process named by a link (/dev/stdout redirected to a file by a shell) is written
// where it stands, at its offset: the file gets the bytes and the link stays; a read-only one is refused.
TEST_F(SafeFile, ADescriptorNamedByALinkIsWrittenWhereItStands) {
  const fs::path file = dir_ / "redirected";
  const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_APPEND, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(write(fd, "a\n", 2), 2);
  const std::string by_fd = "/proc/self/fd/" + std::to_string(fd);
  fs::create_symlink(by_fd, dir_ / "out");
  EXPECT_EQ(named_output_problem(dir_ / "out"), "");
  write_named_output(dir_ / "out", "b\n");
  write_named_output(by_fd, "c\n");
  write_named_output("/dev/fd/" + std::to_string(fd), "d\n");
  close(fd);
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir_ / "out")));
  const auto text = [&] {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(text(), "a\nb\nc\nd\n");
  const int ro = open(file.c_str(), O_RDONLY);
  ASSERT_GE(ro, 0);
  EXPECT_THROW(write_named_output("/proc/self/fd/" + std::to_string(ro), "x"), std::system_error);
  close(ro);
  EXPECT_EQ(text(), "a\nb\nc\nd\n");
}

TEST_F(SafeFile, WriteFileAtomicallyReplacesALinkNotItsTarget) {
  std::ofstream(dir_ / "target") << "theirs";
  fs::create_symlink(dir_ / "target", dir_ / "out.json");
  write_file_atomically(dir_ / "out.json", "ours");
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir_ / "out.json")));
  std::ifstream ours(dir_ / "out.json"), theirs(dir_ / "target");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(ours), {}), "ours");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(theirs), {}), "theirs");
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

// Holders that take the lock and give it up as hfbake does (locked, named, removed while held, closed), one
// after another, while a FolderLock waits: whatever moment it opens the file at (a holder's file it opened
// may be removed before it looks at it), it never sees a problem, only a holder or the lock.
TEST_F(SafeFile, AFolderLockWaitsOutHoldersThatComeAndGo) {
  const fs::path lock = dir_ / ".lock";
  std::atomic<bool> stop{false};
  std::thread holders([&] {
    while (!stop) {
      const int fd = open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
      if (fd < 0) continue;
      if (flock(fd, LOCK_EX | LOCK_NB) == 0) {
        (void)!write(fd, "1@h", 3);
        unlink(lock.c_str());
      }
      close(fd);
    }
  });
  int held = 0;
  std::string problem;
  for (int i = 0; i < 600 && problem.empty(); ++i) {
    FolderLock l(lock, std::chrono::milliseconds(0));
    problem = l.problem();
    held += l.held() ? 1 : 0;
  }
  stop = true;
  holders.join();
  EXPECT_EQ(problem, "");
  EXPECT_GT(held, 0);
}

// A held lock's folder moved away while the lock is held, and its name taken by a link to another folder
// (holding a file of the lock's name) or by a new folder whose own lock another holder took: the lock's end
// removes its own file, at the folder's new name, and neither of the others.
TEST_F(SafeFile, AFolderLockRemovesOnlyItsOwnFileWhereverItsFolderWent) {
  for (const bool link : {true, false}) {
    SCOPED_TRACE(link ? "a link at the folder's name" : "a new folder at its name");
    const fs::path out = dir_ / "out", moved = dir_ / "out.moved", elsewhere = dir_ / "elsewhere";
    fs::create_directories(out);
    fs::create_directories(elsewhere);
    std::ofstream(elsewhere / ".lock") << "precious";
    std::optional<FolderLock> other;
    {
      FolderLock l(out / ".lock");
      ASSERT_TRUE(l.held()) << l.problem();
      fs::rename(out, moved);
      if (link) {
        fs::create_directory_symlink(elsewhere, out);
      } else {
        fs::create_directories(out);
        other.emplace(out / ".lock");
        ASSERT_TRUE(other->held()) << other->problem();
      }
    }
    EXPECT_FALSE(fs::exists(moved / ".lock"));
    EXPECT_TRUE(fs::exists(elsewhere / ".lock"));
    if (!link) {
      EXPECT_TRUE(fs::exists(out / ".lock")) << "the new holder's lock was removed";
      FolderLock third(out / ".lock");
      EXPECT_FALSE(third.held()) << "a third process took the lock the second holds";
    }
    other.reset();
    fs::remove_all(out), fs::remove_all(moved), fs::remove_all(elsewhere);
  }
}

}  // namespace
}  // namespace hfbake
