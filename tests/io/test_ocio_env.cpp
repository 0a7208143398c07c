// $OCIO is honoured: with it set (before the first colour conversion of the process), hfbake uses that
// config instead of its built-in one. A separate executable, since the config is chosen once per process.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "io/color.hpp"
#include "temp_folder.hpp"

namespace hfbake {
namespace {

// A config of a linear reference space "lin" and one more colour space, `name`, whose transform to the
// reference is `to_reference` (YAML); files it names are looked up in `search_path`.
std::string config_with(const std::string& name, const std::string& to_reference,
                        const std::string& search_path = ".") {
  return "ocio_profile_version: 2\nsearch_path: \"" + search_path +
         "\"\nroles:\n  default: lin\n  scene_linear: lin\nfile_rules:\n"
         "  - !<Rule> {name: Default, colorspace: default}\ndisplays:\n  d:\n"
         "    - !<View> {name: v, colorspace: lin}\ncolorspaces:\n  - !<ColorSpace>\n    name: lin\n"
         "  - !<ColorSpace>\n    name: " +
         name + "\n    to_scene_reference: " + to_reference + "\n";
}

TEST(OcioEnvironment, UsesTheConfigNamedByOcio) {
  test::TempFolder dir;
  // A config whose only input space halves values: unmistakably not the built-in one.
  const auto file = dir / "test.ocio";
  std::ofstream(file) << config_with(
      "half_gain", "!<MatrixTransform> {matrix: [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1]}");
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

// OpenColorIO reads a config and its LUTs whole, blocking: a LUT that is a pipe hung the process past its
// signals, /dev/zero filled its memory. A config naming one (used or not) is refused in one line naming the
// colour space and the file, before anything reads it. A writer that opens the pipe and closes it again
// lets a read that does happen end (at EOF) instead of hanging the test.
TEST(OcioEnvironment, ALutThatIsNoRegularFileIsRefusedUnread) {
  test::TempFolder dir;
  const std::string fifo = (dir / "lut.spi1d").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const auto file = dir / "pipe.ocio";
  std::ofstream(file) << config_with(
      "piped", "!<GroupTransform> {children: [!<FileTransform> {src: lut.spi1d}]}", dir.path().string());
  std::thread writer([&] {
    const int fd = open(fifo.c_str(), O_WRONLY);  // returns once some reader opened it
    if (fd >= 0) close(fd);
  });
  setenv("OCIO", file.c_str(), 1);
  std::string message;
  try {
    check_colorspace("lin", {"job.json", "/environment/colorspace"});
  } catch (const InputError& e) {
    message = e.line();
  }
  // Nobody read the pipe: open it for reading (without blocking) so the writer returns.
  const int rd = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  writer.join();
  if (rd >= 0) close(rd);
  EXPECT_NE(message.find("job.json: /environment/colorspace: "), std::string::npos) << message;
  EXPECT_NE(message.find("colour space \"piped\" reads the LUT " + fifo + ": not a regular file"),
            std::string::npos)
      << message;
  unsetenv("OCIO");
}

// $OCIO itself a folder or a device: refused by name, not read.
TEST(OcioEnvironment, AConfigThatIsNoRegularFileIsRefusedUnread) {
  setenv("OCIO", "/dev/zero", 1);
  std::string message;
  try {
    check_colorspace("lin", {"job.json", "/environment/colorspace"});
  } catch (const InputError& e) {
    message = e.line();
  }
  EXPECT_NE(message.find("the config /dev/zero: not a regular file"), std::string::npos) << message;
  unsetenv("OCIO");
}

}  // namespace
}  // namespace hfbake
