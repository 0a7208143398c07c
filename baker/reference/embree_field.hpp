// The height field as an Embree 3 scene: the surface of docs/contract.md, closed into a solid.
//
// Surface: a vertex at every texel center, two triangles per quad split along the diagonal from texel
// (i+1, j) to (i, j+1) (Embree's grid and quad split), as RTC_GEOMETRY_TYPE_GRID (default) or as a triangle
// mesh with the same split (for the speed comparison; both give the same surface).
//
// Solid: rays may never pass under the sheet. The sheet is watertight (robust scene), and a "skirt" closes
// it: vertical walls hang from every border edge down to z_bottom = min height - (height range + 1 texel),
// plus a bottom cap, so a ray that leaves a border texel going outwards and downwards hits the wall instead
// of sliding under the field. Above the border edge nothing is in the way: rays escape (wrap clamp).
//
// wrap repeat: the field tiles. The base tile (with its seam row and column: (W+1) x (H+1) vertices) is
// instanced (2T+1)^2 times, T = repeat_tiles, and the skirt surrounds the whole block. Every receiver of the
// central tile therefore sees occluders at least T field sizes away in every direction (distance bound
// T * min(W, H) * texel_size); beyond the block rays escape.
#pragma once

#include <embree3/rtcore.h>

#include <string>

#include "field/height_field.hpp"

namespace hfbake::reference {

enum class GeometryKind { grid, triangles, quads };
GeometryKind geometry_kind(const std::string& name);  // "grid", "triangles", "quads" (else quads)
const char* geometry_name(GeometryKind kind);
// Embree's geometry and BVH, for the memory estimate: bytes a texel, and bytes that do not grow with the
// field (the device, its threads' allocators, the builders' blocks). Fitted to the rise of the resident
// memory while the reference traces, at 512^2, 2048^2 and 4096^2 (docs/large-fields.md).
double embree_bytes_per_texel(GeometryKind kind);
double embree_fixed_bytes(GeometryKind kind);

class EmbreeField {
 public:
  EmbreeField(const HeightField& field, GeometryKind kind, int repeat_tiles);
  ~EmbreeField();
  EmbreeField(const EmbreeField&) = delete;
  EmbreeField& operator=(const EmbreeField&) = delete;

  RTCScene scene() const { return scene_; }
  // Ray origins are offset by this much along the normal (world units): 1e-3 texel, or 16 float ulps of
  // the largest coordinate when that is larger.
  double epsilon() const { return epsilon_; }
  // The smallest lift float coordinates resolve: 16 ulps of the largest coordinate (what epsilon() never
  // goes below). Horizon bisection lifts its receivers by max(1e-5 texel, this): a larger lift raises the
  // receiver by a visible fraction of a steep near caster's rise.
  double float_floor() const { return float_floor_; }
  double z_bottom() const { return z_bottom_; }

 private:
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr, tile_ = nullptr;
  double epsilon_ = 0, z_bottom_ = 0, float_floor_ = 0;
};

}  // namespace hfbake::reference
