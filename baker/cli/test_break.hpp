// A test-only switch: HFBAKE_TEST_BREAK=<method or stem>[,...] adds 0.05 to every value the named methods
// bake, so tests (and anyone checking a nightly set-up) can see a regression caught end to end: thresholds
// and baselines fail, the exit status is 1 and report.html marks the metric. Never set in production.
#pragma once

#include <cstdlib>
#include <sstream>
#include <string>

#include "core/layers.hpp"

namespace hfbake {

inline bool test_break_applies(const std::string& method, const std::string& stem) {
  const char* v = std::getenv("HFBAKE_TEST_BREAK");
  if (!v || !*v) return false;
  std::istringstream names(v);
  for (std::string n; std::getline(names, n, ',');)
    if (n == method || n == stem) return true;
  return false;
}

// Returns true when the layers were broken.
inline bool apply_test_break(const std::string& method, const std::string& stem, LayerSet& layers) {
  if (!test_break_applies(method, stem)) return false;
  for (Layer& l : layers.layers)
    for (float& x : l.data) x += 0.05f;
  layers.attributes.emplace_back("hfbake:test_break", "HFBAKE_TEST_BREAK added 0.05 to every value");
  return true;
}

}  // namespace hfbake
