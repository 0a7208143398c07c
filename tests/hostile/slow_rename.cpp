// A preload library for the tests that stop a bake while it moves its outputs into place: rename(2) onto a
// path that ends in $HFBAKE_TEST_SLOW_RENAME (outside a staging folder, links resolved) first creates the
// file $HFBAKE_TEST_SLOW_RENAME_FLAG (the test then knows the moves have begun) and waits
// $HFBAKE_TEST_SLOW_RENAME_MS milliseconds, signals or not, then renames.
#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <ctime>

extern "C" int rename(const char* from, const char* to) {
  using Rename = int (*)(const char*, const char*);
  static const Rename real = reinterpret_cast<Rename>(dlsym(RTLD_NEXT, "rename"));
  const char* tail = std::getenv("HFBAKE_TEST_SLOW_RENAME");
  const std::size_t n = tail ? std::strlen(tail) : 0, m = std::strlen(to);
  // The folder `to` is in, its links resolved (hfbake renames through /proc/self/fd/N, the folders it holds).
  char folder[4096] = {}, resolved[PATH_MAX] = {};
  std::strncpy(folder, to, sizeof folder - 1);
  if (char* slash = std::strrchr(folder, '/')) *slash = '\0';
  const bool in_stage = std::strstr(to, ".hfbake-staging-") ||
                        (realpath(folder, resolved) && std::strstr(resolved, ".hfbake-staging-"));
  if (n > 0 && m >= n && std::strcmp(to + m - n, tail) == 0 && !in_stage) {
    if (const char* flag = std::getenv("HFBAKE_TEST_SLOW_RENAME_FLAG")) {
      const int fd = open(flag, O_CREAT | O_WRONLY | O_CLOEXEC, 0644);
      if (fd >= 0) close(fd);
    }
    const char* ms = std::getenv("HFBAKE_TEST_SLOW_RENAME_MS");
    const long wait = ms ? std::atol(ms) : 3000;
    timespec left{wait / 1000, (wait % 1000) * 1000000L};
    while (nanosleep(&left, &left) != 0 && errno == EINTR) {
    }
  }
  return real(from, to);
}
