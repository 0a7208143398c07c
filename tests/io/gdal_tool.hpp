// Running GDAL's command-line tools (gdal-bin) from tests: their output is the independent truth hfbake's
// GDAL reader and GeoTIFF writer are checked against.
#pragma once

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace hfbake::test {

// stdout of `command` (stderr discarded); `status` receives its exit status.
inline std::string run_tool(const std::string& command, int* status = nullptr) {
  std::string out;
  FILE* p = popen((command + " 2>/dev/null").c_str(), "r");
  if (!p) return out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int s = pclose(p);
  if (status) *status = s;
  return out;
}

// `gdalinfo -json FILE` parsed (a null document when the tool fails).
inline nlohmann::json gdalinfo_json(const std::filesystem::path& file) {
  int status = -1;
  const std::string out = run_tool("gdalinfo -json '" + file.string() + "'", &status);
  if (status != 0) return nullptr;
  return nlohmann::json::parse(out, nullptr, false);
}

// `gdalinfo -json OPTIONS FILE` (e.g. "-stats", which also writes FILE.aux.xml beside it).
inline nlohmann::json gdalinfo_json_with(const std::string& options, const std::filesystem::path& file) {
  int status = -1;
  const std::string out = run_tool("gdalinfo -json " + options + " '" + file.string() + "'", &status);
  if (status != 0) return nullptr;
  return nlohmann::json::parse(out, nullptr, false);
}

inline bool have_gdal_tools() {
  int status = -1;
  run_tool("gdalinfo --version", &status);
  return status == 0;
}

}  // namespace hfbake::test
