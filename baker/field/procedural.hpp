// Built-in height fields: the four test surfaces of P2 (Figure 7) and analytic shapes for tests.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

#include "field/height_field.hpp"

namespace hfbake {

enum class ProceduralKind {
  fractal,
  bricks,
  sines,
  blocks,
  flat,
  slope,
  trench,
  pit,
  cone,
  // Hard terrain: the shapes users bring that the P2 fields do not have.
  terraces,
  craters,
  ridges,
  rough
};
inline constexpr ProceduralKind kLastProceduralKind = ProceduralKind::rough;

struct ProceduralSpec {
  ProceduralKind kind = ProceduralKind::fractal;
  int width = 256, height = 256;
  std::uint64_t seed = 1;
  // Shape parameters in world units / degrees; which ones a kind uses is documented in procedural.cpp
  // and in schemas/job.schema.json. Heights are world units for texel_size 1 (scaled with texel_size).
  double amplitude = 0;     // vertical scale (0 = the kind's default)
  double feature_size = 0;  // horizontal feature scale in texels (0 = the kind's default)
  // slope: plane angle; trench: wall angle; cone: flank angle (default 30); rough: median slope (default 70).
  double angle_deg = std::numeric_limits<double>::quiet_NaN();  // NaN: the kind's default
  double aspect_deg = 0;  // slope: downhill azimuth (direction the plane faces)
  double radius = 0;      // pit: radius in texels (0 = width / 4)
  double depth = 0;       // pit: depth in texels (0 = radius)
  double step = 0;        // terraces: height of one step in texels (0 = amplitude / 3)
};

bool parse_procedural_kind(const std::string& name, ProceduralKind& kind);
const char* procedural_kind_name(ProceduralKind kind);

// Deterministic in (spec): the same spec gives the same bits on every machine and thread count.
HeightField make_procedural(const ProceduralSpec& spec, double texel_size, Wrap wrap);

}  // namespace hfbake
