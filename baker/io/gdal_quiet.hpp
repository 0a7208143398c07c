// GDAL set up once per process (drivers registered) and quiet per call: its messages are collected and
// handed to hfbake's one-line errors instead of being printed on stderr.
#pragma once

#include <cpl_error.h>
#include <gdal.h>

#include <mutex>
#include <string>

namespace hfbake {

class GdalQuiet {
 public:
  GdalQuiet() {
    static std::once_flag once;
    std::call_once(once, [] { GDALAllRegister(); });
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
  }
  ~GdalQuiet() { CPLPopErrorHandler(); }
  GdalQuiet(const GdalQuiet&) = delete;
  GdalQuiet& operator=(const GdalQuiet&) = delete;

  // GDAL's last message (first line), or "unknown error".
  std::string error() const {
    std::string s = CPLGetLastErrorMsg();
    const auto nl = s.find('\n');
    if (nl != std::string::npos) s.resize(nl);
    return s.empty() ? std::string("unknown error") : s;
  }
  // The same for a message about `file`, which the error line names already: GDAL's leading "<file>, " or
  // "<file>: " is left out, so that the line names the file once.
  std::string error(const std::string& file) const {
    std::string s = error();
    if (!file.empty() && s.compare(0, file.size(), file) == 0 && s.size() > file.size() + 2 &&
        (s.compare(file.size(), 2, ", ") == 0 || s.compare(file.size(), 2, ": ") == 0))
      s.erase(0, file.size() + 2);
    return s;
  }
};

}  // namespace hfbake
