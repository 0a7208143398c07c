#include "core/safe_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <vector>

namespace hfbake {
namespace fs = std::filesystem;

namespace {

// The process's umask, read once before main (umask(2) can only be read by setting it: done while no other
// thread creates files).
const mode_t kProcessUmask = [] {
  const mode_t m = umask(022);
  umask(m);
  return m;
}();

std::system_error system_error(int err, const std::string& what) {
  return std::system_error(err, std::generic_category(), what);
}

// Removes the entry `name` of the folder `dir` (a descriptor), recursing into it only when it is a folder
// itself (opened with O_NOFOLLOW | O_DIRECTORY).
bool remove_entry(int dir, const char* name) {
  if (unlinkat(dir, name, 0) == 0 || errno == ENOENT) return true;
  if (errno != EISDIR && errno != EPERM) return false;
  const int sub = openat(dir, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (sub < 0) return false;
  bool ok = true;
  std::vector<std::string> names;
  if (DIR* d = fdopendir(dup(sub))) {
    while (const dirent* e = readdir(d))
      if (std::strcmp(e->d_name, ".") != 0 && std::strcmp(e->d_name, "..") != 0)
        names.emplace_back(e->d_name);
    closedir(d);
  } else {
    ok = false;
  }
  for (const std::string& n : names) ok = remove_entry(sub, n.c_str()) && ok;
  close(sub);
  return (unlinkat(dir, name, AT_REMOVEDIR) == 0 || errno == ENOENT) && ok;
}

}  // namespace

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "localhost";
  return buf;
}

bool is_real_directory(const fs::path& path) {
  struct stat st {};
  return lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

bool remove_tree(const fs::path& path) {
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  const int dir = open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return errno == ENOENT;
  const bool ok = remove_entry(dir, path.filename().c_str());
  close(dir);
  return ok;
}

namespace {

// Whether `name` in the folder `dir` is the file open as `fd` (not a link, not another file since).
bool names_file(int dir, const std::string& name, int fd) {
  struct stat held {
  }, now{};
  return fstat(fd, &held) == 0 && fstatat(dir, name.c_str(), &now, AT_SYMLINK_NOFOLLOW) == 0 &&
         held.st_ino == now.st_ino && held.st_dev == now.st_dev;
}

}  // namespace

std::string FolderLock::holder_words() const {
  const bool here = holder_ == std::to_string(getpid()) + "@" + host_name();
  return (here ? "another bake in this process (" : "another hfbake process (") + holder_ + ")";
}

FolderLock::FolderLock(const fs::path& path, std::chrono::milliseconds patience) : path_(path) {
  const auto until = std::chrono::steady_clock::now() + patience;
  for (try_lock(); !held() && problem_.empty() && std::chrono::steady_clock::now() < until; try_lock())
    usleep(10000);
}

void FolderLock::try_lock() {
  holder_.clear();
  // The folder, once: the lock is made, checked and removed through it, so a folder moved away and
  // replaced (by another folder, or a link to one) while the lock is held never has its file removed.
  if (dir_ < 0) {
    const fs::path parent = path_.has_parent_path() ? path_.parent_path() : fs::path(".");
    dir_ = open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_ < 0) {
      problem_ = std::error_code(errno, std::generic_category()).message() + " (its folder)";
      return;
    }
  }
  const std::string name = path_.filename().string();
  // The file locked must still be the one at `path_` (a holder that finished removed it, and the next one
  // made another): else lock again.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = openat(dir_, name.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0) {
      problem_ = std::error_code(errno, std::generic_category()).message() + " (a link or a folder?)";
      return;
    }
    struct stat own {};
    const bool seen = fstat(fd, &own) == 0;
    if (seen && S_ISREG(own.st_mode) && own.st_nlink == 0) {
      close(fd);  // its holder removed it since it was opened (gave the lock up): open the name again
      continue;
    }
    if (!seen || !S_ISREG(own.st_mode) || own.st_nlink != 1) {
      problem_ =
          S_ISREG(own.st_mode) ? "a file with another name elsewhere (a hard link)" : "not a regular file";
      close(fd);
      return;
    }
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      // The holder writes its name just after it locked: give it up to 0.2 s to appear.
      char buf[300] = {};
      ssize_t n = 0;
      for (int wait = 0; wait < 40 && (n = pread(fd, buf, sizeof buf - 1, 0)) <= 0; ++wait) usleep(5000);
      holder_ = n > 0 ? std::string(buf, std::size_t(n)) : "another process";
      close(fd);
      return;
    }
    if (names_file(dir_, name, fd)) {
      const std::string me = std::to_string(getpid()) + "@" + host_name();
      if (ftruncate(fd, 0) == 0 && pwrite(fd, me.data(), me.size(), 0) < 0) holder_.clear();
      fd_ = fd;
      return;
    }
    close(fd);
  }
  problem_ = "the lock file keeps changing";
}

FolderLock::~FolderLock() {
  // While held, and only the file this lock holds (a process waiting on it locks again: see try_lock).
  if (fd_ >= 0 && names_file(dir_, path_.filename().string(), fd_))
    unlinkat(dir_, path_.filename().c_str(), 0);
  if (fd_ >= 0) close(fd_);
  if (dir_ >= 0) close(dir_);
}

int open_regular_file(const fs::path& path, std::string& why) {
  const int fd = open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    why = std::error_code(errno, std::generic_category()).message();
    return -1;
  }
  struct stat st {};
  if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    why = "not a regular file";
    if (S_ISDIR(st.st_mode)) why += " (a folder)";
    if (S_ISFIFO(st.st_mode)) why += " (a FIFO)";
    if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) why += " (a device)";
    close(fd);
    return -1;
  }
  fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  return fd;
}

bool read_at(int fd, void* data, std::size_t n, std::uint64_t offset) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    const ssize_t got = pread(fd, p, n, off_t(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    p += got, n -= std::size_t(got), offset += std::uint64_t(got);
  }
  return true;
}

namespace {
struct TemporaryOwner {
  std::string tag;
  pid_t pid = 0;  // the process that set it: a forked child is not its owner
};
TemporaryOwner& temporary_owner_tag() {
  static TemporaryOwner owner;
  return owner;
}
std::string temporary_owner_or_pid() {
  const TemporaryOwner& o = temporary_owner_tag();
  return o.tag.empty() || o.pid != getpid() ? std::to_string(getpid()) : o.tag;
}
}  // namespace

void set_temporary_owner(const std::string& owner) {
  temporary_owner_tag() = {owner, getpid()};
}

TempFile::TempFile(const fs::path& final, const std::string& tag) : final_(final) {
  std::string name = final.string() + ".tmp-" + (tag.empty() ? temporary_owner_or_pid() : tag) + "-XXXXXX";
  fd_ = mkostemp(name.data(), O_CLOEXEC);
  if (fd_ < 0) throw system_error(errno, "cannot create a temporary file beside " + final.string());
  tmp_ = name;
  fchmod(fd_, 0666 & ~kProcessUmask);
}

TempFolder::TempFolder(const fs::path& final) {
  std::string name = final.string() + ".tmp-" + temporary_owner_or_pid() + "-XXXXXX";
  if (!mkdtemp(name.data()))
    throw system_error(errno, "cannot create a temporary folder beside " + final.string());
  dir_ = name;
}

TempFolder::~TempFolder() {
  if (!dir_.empty()) remove_tree(dir_);
}

TempFile::~TempFile() {
  if (fd_ >= 0) close(fd_);
  if (!committed_ && !tmp_.empty()) unlink(tmp_.c_str());
}

bool TempFile::write(const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t put = ::write(fd_, p, n);
    if (put < 0 && errno == EINTR) continue;
    if (put <= 0) return false;
    p += put, n -= std::size_t(put);
  }
  return true;
}

void TempFile::commit() {
  const int fd = fd_;
  fd_ = -1;
  if (fsync(fd) != 0 && errno != EINVAL) {  // EINVAL: a file system without fsync
    const int e = errno;
    close(fd);
    throw system_error(e, "cannot write " + tmp_.string());
  }
  if (close(fd) != 0) throw system_error(errno, "cannot write " + tmp_.string());
  if (rename(tmp_.c_str(), final_.c_str()) != 0)
    throw system_error(errno, "cannot rename into " + final_.string());
  committed_ = true;
  sync_folder(final_.has_parent_path() ? final_.parent_path() : fs::path("."));
}

int sync_file(const fs::path& path) {
  const int fd = open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return errno;
  const int r = fsync(fd) != 0 && errno != EINVAL ? errno : 0;
  close(fd);
  return r;
}

void sync_folder(const fs::path& folder) {
  const int fd = open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;  // the rename stands; only its durability is not asked for
  (void)fsync(fd);
  close(fd);
}

void write_file_atomically(const fs::path& final, std::string_view bytes) {
  TempFile tmp(final);
  if (!tmp.write(bytes)) throw system_error(errno ? errno : EIO, "cannot write " + final.string());
  tmp.commit();
}

int descriptor_named(const fs::path& file) {
  std::error_code ec;
  fs::path p = fs::absolute(file, ec);
  if (ec) return -1;
  const std::string own = "/proc/" + std::to_string(getpid()) + "/fd/";
  for (int hops = 0; hops < 40; ++hops) {
    const std::string s = p.lexically_normal().string();
    for (const std::string& prefix : {std::string("/proc/self/fd/"), std::string("/dev/fd/"), own})
      if (s.rfind(prefix, 0) == 0) {
        const std::string n = s.substr(prefix.size());
        if (n.empty() || n.size() > 9 || n.find_first_not_of("0123456789") != std::string::npos) return -1;
        return std::stoi(n);
      }
    if (!fs::is_symlink(fs::symlink_status(p, ec))) return -1;
    const fs::path target = fs::read_symlink(p, ec);
    if (ec) return -1;
    p = target.is_absolute() ? target : p.parent_path() / target;
  }
  return -1;
}

namespace {

// A FIFO or a character device, or a link to one: written through, never replaced by a rename.
bool is_stream(const fs::path& file) {
  struct stat st;
  return stat(file.c_str(), &st) == 0 && (S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode));
}

void write_all(int fd, std::string_view bytes, const fs::path& file) {
  for (std::size_t done = 0; done < bytes.size();) {
    const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw system_error(n < 0 ? errno : EIO, "cannot write " + file.string());
    done += std::size_t(n);
  }
}

}  // namespace

void write_named_output(const fs::path& file, std::string_view bytes) {
  // A descriptor of this process (a shell's redirection of standard output to a file, say) is written
  // where it stands, never replaced by a rename, whatever it is open on.
  if (const int fd = descriptor_named(file); fd >= 0) {
    const int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || (flags & O_ACCMODE) == O_RDONLY)
      throw system_error(flags < 0 ? errno : EBADF, "cannot write " + file.string());
    std::fflush(nullptr);  // what stdio holds for the same descriptor comes first
    write_all(fd, bytes, file);
    return;
  }
  if (!is_stream(file)) {
    if (const fs::path dir = fs::absolute(file).parent_path(); !fs::exists(dir)) fs::create_directories(dir);
    write_file_atomically(file, bytes);
    return;
  }
  const int fd = open(file.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw system_error(errno, "cannot open " + file.string());
  try {
    write_all(fd, bytes, file);
  } catch (...) {
    close(fd);
    throw;
  }
  if (close(fd) != 0 && errno != EINTR) throw system_error(errno, "cannot write " + file.string());
}

std::string named_output_problem(const fs::path& file) {
  if (descriptor_named(file) >= 0 || is_stream(file)) return "";  // written through, whatever its folder
  std::error_code ec;
  if (fs::is_directory(file, ec)) return "is a folder: name the file to write";
  fs::path dir = fs::absolute(file, ec).parent_path();
  if (ec) return "cannot resolve the path: " + ec.message();
  while (fs::symlink_status(dir, ec).type() == fs::file_type::not_found && dir.has_relative_path())
    dir = dir.parent_path();
  if (!fs::is_directory(dir, ec)) return dir.string() + " is not a folder";
  if (access(dir.c_str(), W_OK | X_OK) != 0)
    return "cannot write into " + dir.string() + ": " + std::strerror(errno);
  return "";
}

std::string not_a_lock_file(const fs::path& lock, const std::string& why) {
  return lock.string() + " is no lock file of hfbake's (" + why + "): remove it";
}

std::string lock_name_problem(const fs::path& lock) {
  std::error_code ec;
  const fs::file_status s = fs::symlink_status(lock, ec);
  if (!fs::exists(s)) return "";
  if (fs::is_regular_file(s)) {
    // FolderLock's own words for a file it would not take.
    const std::uintmax_t links = fs::hard_link_count(lock, ec);
    return !ec && links > 1 ? not_a_lock_file(lock, "a file with another name elsewhere (a hard link)") : "";
  }
  return not_a_lock_file(lock, fs::is_symlink(s) ? "a link" : "not a file");
}

HeldFolder::HeldFolder(const std::filesystem::path& dir, bool follow_link) {
  fd_ = ::open(dir.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC | (follow_link ? 0 : O_NOFOLLOW));
  if (fd_ < 0) return;
  const std::filesystem::path proc = "/proc/self/fd/" + std::to_string(fd_);
  struct stat a {
  }, b{};
  // The magic link is the folder itself where /proc is mounted; else the name is all there is.
  path_ =
      ::stat(proc.c_str(), &a) == 0 && ::fstat(fd_, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino
          ? proc
          : dir;
}

HeldFolder::HeldFolder(HeldFolder&& other) noexcept : fd_(other.fd_), path_(std::move(other.path_)) {
  other.fd_ = -1;
}

HeldFolder& HeldFolder::operator=(HeldFolder&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_, path_ = std::move(other.path_);
    other.fd_ = -1;
  }
  return *this;
}

HeldFolder::~HeldFolder() {
  if (fd_ >= 0) ::close(fd_);
}

}  // namespace hfbake
