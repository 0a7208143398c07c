// Every output layer is checked finite before anything is written: a NaN or an infinity fails the
// job with a line naming the method, the layer, the first texel and its channel; horizon_distance may be
// +inf (nothing behind the texel) and nothing else may.
#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>
#include <string>

#include "cli/outputs.hpp"

namespace hfbake {
namespace {

LayerSet layers_5x4() {
  LayerSet s;
  s.width = 5;
  s.height = 4;
  s.add("ao", mono_channels());
  s.add("direct", rgb_channels());
  for (Layer& l : s.layers)
    for (float& v : l.data) v = 0.5f;
  return s;
}

std::string failure(const LayerSet& s) {
  try {
    check_layers_finite("p1", s);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(FiniteOutputs, FiniteLayersPass) {
  EXPECT_EQ(failure(layers_5x4()), "");
}

TEST(FiniteOutputs, TheFirstNonFiniteTexelIsNamedWithItsLayerAndChannel) {
  LayerSet s = layers_5x4();
  // direct is RGB: texel (3, 2) is index 2 * 5 + 3 = 13, its G value 13 * 3 + 1.
  s.layers[1].data[13 * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
  s.layers[1].data[19 * 3 + 2] = std::numeric_limits<float>::infinity();  // a later one is not named
  EXPECT_EQ(failure(s).rfind("p1: layer direct: texel (3, 2) channel direct.G is nan", 0), 0u) << failure(s);
  LayerSet t = layers_5x4();
  t.layers[0].data[4] = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(failure(t).rfind("p1: layer ao: texel (4, 0) channel ao.Y is -inf", 0), 0u) << failure(t);
}

TEST(FiniteOutputs, HorizonDistanceMayBePlusInfinityOnly) {
  LayerSet s = layers_5x4();
  Layer& d = s.add("horizon_distance", {"000", "001"});
  for (float& v : d.data) v = 2.0f;
  d.data[7] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(failure(s), "");
  d.data[9] = std::numeric_limits<float>::quiet_NaN();  // texel 4, channel 001
  EXPECT_EQ(
      failure(s).rfind("p1: layer horizon_distance: texel (4, 0) channel horizon_distance.001 is nan", 0), 0u)
      << failure(s);
}

// A layer of many chunks (the check tests 4096 values at a time): the first bad value is named wherever
// it lies, in a whole chunk or in the last, partial one, and one bad value among 72 000 is found.
TEST(FiniteOutputs, TheFirstBadValueOfALargeLayerIsFoundInEveryChunk) {
  LayerSet s;
  s.width = 120, s.height = 100;
  Layer& h = s.add("horizon", indexed_channels(6));  // 72 000 values: 17 whole chunks and a partial one
  for (float& v : h.data) v = 0.25f;
  EXPECT_EQ(failure(s), "");
  for (const std::size_t at : {std::size_t(0), std::size_t(4095), std::size_t(4096), std::size_t(50001),
                               std::size_t(69631), std::size_t(69632), std::size_t(71999)}) {
    h.data[at] = std::numeric_limits<float>::quiet_NaN();
    const std::size_t texel = at / 6;
    const std::string want = "p1: layer horizon: texel (" + std::to_string(texel % 120) + ", " +
                             std::to_string(texel / 120) + ") channel horizon.00" + std::to_string(at % 6) +
                             " is nan";
    EXPECT_EQ(failure(s).rfind(want, 0), 0u) << at << ": " << failure(s);
    h.data[at] = 0.25f;
  }
}

// A fraction of the sky beyond [0, 1] by more than a quadrature's error: ao up to 1.026 came out of a field
// of 1e-9 m texels; 1.0019 is what p1 with 4 directions gives on a small fractal.
TEST(FiniteOutputs, FractionsOfTheSkyStayInZeroOne) {
  LayerSet s = layers_5x4();
  s.layers[0].data[6] = 1.0019f;
  s.layers[0].data[7] = -0.01f;
  EXPECT_EQ(failure(s), "");
  s.layers[0].data[8] = 1.06f;
  EXPECT_EQ(failure(s).rfind("p1: layer ao: texel (3, 1) channel ao.Y is 1.06, outside [0, 1]", 0), 0u)
      << failure(s);
  LayerSet t = layers_5x4();
  for (float& v : t.layers[1].data) v = 7.0f;  // direct is light, not a fraction
  EXPECT_EQ(failure(t), "");
}

}  // namespace
}  // namespace hfbake
