// $OCIO is honoured: with it set (before the first colour conversion of the process), hfbake uses that
// config instead of its built-in one. A separate executable, since the config is chosen once per process.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "io/color.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {

TEST(OcioEnvironment, UsesTheConfigNamedByOcio) {
  test::TempFolder dir;
  // A config whose only input space halves values: unmistakably not the built-in one.
  const auto file = dir / "test.ocio";
  std::ofstream(file) << R"(ocio_profile_version: 2
roles:
  default: lin
  scene_linear: lin
file_rules:
  - !<Rule> {name: Default, colorspace: default}
displays:
  d:
    - !<View> {name: v, colorspace: lin}
colorspaces:
  - !<ColorSpace>
    name: lin
  - !<ColorSpace>
    name: half_gain
    to_scene_reference: !<MatrixTransform> {matrix: [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1]}
)";
  setenv("OCIO", file.c_str(), 1);
  std::vector<float> px = {0.8f, 0.4f, 0.2f};
  convert_to_linear(px, 3, "half_gain", {});
  EXPECT_FLOAT_EQ(px[0], 0.4f);
  EXPECT_FLOAT_EQ(px[2], 0.1f);
  EXPECT_EQ(ocio_config_description(), "$OCIO (" + file.string() + ")");
  // The built-in names are not there.
  EXPECT_THROW(convert_to_linear(px, 3, "sRGB - Texture", {}), std::exception);
  unsetenv("OCIO");
}

}  // namespace
}  // namespace hfbake
