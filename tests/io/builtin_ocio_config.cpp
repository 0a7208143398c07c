// test_io checks hfbake's built-in OpenColorIO config: a user's $OCIO must not change what it tests.
// (The config is chosen at the first colour conversion, after static initialisation; test_ocio_env
// covers $OCIO itself.)
#include <cstdlib>

namespace {
const bool kOcioUnset = [] {
  unsetenv("OCIO");
  return true;
}();
}  // namespace
