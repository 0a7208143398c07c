// Files whose names another user or process could have planted: opened without blocking and only when
// regular, created under names nobody else holds (O_CREAT | O_EXCL never opens an existing name, a symbolic
// link included), and moved into place by rename(2), which replaces a link instead of following it.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace hfbake {

// Opens `path` read-only with O_NONBLOCK (a FIFO or a device never blocks the open) and returns the
// descriptor when it is a regular file (fstat; O_NONBLOCK cleared again). Otherwise -1 and `why` says
// what it is ("not a regular file (a folder)", "(a FIFO)", "(a device)", or the error).
int open_regular_file(const std::filesystem::path& path, std::string& why);

// Reads exactly `n` bytes at `offset`; false on a short read or an error.
bool read_at(int fd, void* data, std::size_t n, std::uint64_t offset);

// This machine's name (gethostname; "localhost" where it has none): the host in "<pid>@<host>", how lock
// files, owner records and shard files name the process that wrote them.
std::string host_name();

// The owner a temporary's name carries ("<final>.tmp-<owner>-XXXXXX"), so that a later process can tell a
// dead process's temporaries from a live one's and remove them: set once at start by the program (the
// command and the Python module: <pid>+<start>@<host>, cli/outputs.hpp temporary_owner); the process id
// until then.
void set_temporary_owner(const std::string& owner);

// A new file beside `final`, named "<final>.tmp-<tag>-XXXXXX" (tag "": the temporary owner; mkostemp:
// created by this call, mode as an ordinary file under the umask). Removed by the destructor unless
// committed. Errors: std::system_error.
class TempFile {
 public:
  explicit TempFile(const std::filesystem::path& final, const std::string& tag = "");
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  // Appends all `n` bytes; false on an error (a full disk).
  bool write(const void* data, std::size_t n);
  bool write(std::string_view s) { return write(s.data(), s.size()); }
  // Closes the file (a failed close is an error: NFS reports write errors there) and renames it onto
  // `final` (a link there is replaced, not followed).
  void commit();
  const std::filesystem::path& path() const { return tmp_; }

 private:
  std::filesystem::path final_, tmp_;
  int fd_ = -1;
  bool committed_ = false;
};

// A new folder beside `final`, named "<final>.tmp-<owner>-XXXXXX" (the temporary owner; mkdtemp: created by
// this call, mode 0700), for a library that writes a file by name (GDAL): nothing in it can have been
// planted. Removed with what it holds by the destructor (remove_tree). Errors: std::system_error.
class TempFolder {
 public:
  explicit TempFolder(const std::filesystem::path& final);
  ~TempFolder();
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  const std::filesystem::path& path() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

// `bytes` as the whole content of `final`, through a TempFile. Errors: std::system_error.
void write_file_atomically(const std::filesystem::path& final, std::string_view bytes);

// A file a user names on the command line (hfbake horizon --out, bake --summary, compare --json): written
// through when it is one of this process's descriptors by a link (/dev/stdout, /dev/fd/N, /proc/self/fd/N:
// into the descriptor, whatever it is open on, at its offset), a FIFO or a character device, or a link to
// one (a shell's >(...)), which a rename would replace; atomically (write_file_atomically) otherwise.
// Folders of the path that do not exist yet are made first. Errors: std::system_error.
void write_named_output(const std::filesystem::path& file, std::string_view bytes);

// The descriptor of this process that `file` names through its links (/dev/stdout -> /proc/self/fd/1,
// /dev/fd/N, /proc/<this pid>/fd/N), or -1.
int descriptor_named(const std::filesystem::path& file);

// Why write_named_output could not write `file`, found before a command does its work: "" when it is a
// stream written through, or a name that is not a folder whose nearest existing folder is one this process
// can write into (the missing ones below it are made when the file is written); else the problem (a
// folder at the name, or the folder that is not one or cannot be written into, named).
std::string named_output_problem(const std::filesystem::path& file);

// Durability: what a rename puts in place survives a crash of the machine, not only of the process. A file's
// bytes are flushed to the disk before it is renamed into place, and the folder after (fsync(2)).
// sync_file: 0, or the errno of a write the disk could not take (a full disk found only at the flush).
int sync_file(const std::filesystem::path& path);
void sync_folder(const std::filesystem::path& folder);

// True when `path` is a folder itself (lstat: a link to one is not).
bool is_real_directory(const std::filesystem::path& path);

// A folder held open from the moment it is checked: path() names that folder (/proc/self/fd/<fd>/) whatever
// is renamed, or linked, at its name later, so that a file written or renamed through it never lands
// elsewhere (a link planted while a bake runs). Without /proc, path() is the name it was opened by.
class HeldFolder {
 public:
  HeldFolder() = default;
  // The folder at `dir`; with follow_link false a link there is refused. nullopt-like (held() false) when
  // it is not a folder, or cannot be opened.
  HeldFolder(const std::filesystem::path& dir, bool follow_link);
  HeldFolder(HeldFolder&& other) noexcept;
  HeldFolder& operator=(HeldFolder&& other) noexcept;
  HeldFolder(const HeldFolder&) = delete;
  HeldFolder& operator=(const HeldFolder&) = delete;
  ~HeldFolder();
  bool held() const { return fd_ >= 0; }
  const std::filesystem::path& path() const { return path_; }

 private:
  int fd_ = -1;
  std::filesystem::path path_;
};

// Removes `path` and, when it is a folder itself, everything in it: each entry opened relative to its
// folder (openat, O_NOFOLLOW), so a link anywhere in the tree is removed, never what it points to. False
// when something could not be removed (what could, is).
bool remove_tree(const std::filesystem::path& path);

// The line for a lock's name that holds no lock file of hfbake's: "<lock> is no lock file of hfbake's (why):
// remove it" (why: FolderLock::problem, or what lock_name_problem found).
std::string not_a_lock_file(const std::filesystem::path& lock, const std::string& why);
// What a FolderLock on `lock` would refuse before it is taken: its name taken by anything but a file (a link,
// a folder) or by a file with other names (a hard link), as not_a_lock_file's line; "" when the name is free
// or a file of its own.
std::string lock_name_problem(const std::filesystem::path& lock);

// An exclusive flock(2) on `path` (created if missing, never through a link), held until destruction,
// which removes the file through the folder it was made in, wherever that folder has been moved, and only
// while the name there is still the file it locked: a file at `path` in a folder that replaced it, or one
// made at the name since, is never removed. Taken without waiting
// unless `patience` is given: then tried again every 10 ms while another process holds it, for up to
// `patience`. `held()` is false when another process holds it.
class FolderLock {
 public:
  explicit FolderLock(const std::filesystem::path& path, std::chrono::milliseconds patience = {});
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool held() const { return fd_ >= 0; }
  // When not held: what the holder wrote into the file ("<pid>@<host>").
  const std::string& holder() const { return holder_; }
  // When not held: who holds it in words, "another hfbake process (<pid>@<host>)", or "another bake in
  // this process (<pid>@<host>)" when the holder is this process (a bake on another thread, e.g. from
  // Python).
  std::string holder_words() const;
  // When not held because `path` is no lock file of its own (a link, a folder, a file with another name
  // elsewhere: a hard link, which is never written) or cannot be opened: why; else empty.
  const std::string& problem() const { return problem_; }

 private:
  void try_lock();
  std::filesystem::path path_;
  int dir_ = -1;  // path_'s folder, opened by the first try
  int fd_ = -1;
  std::string holder_, problem_;
};

}  // namespace hfbake
