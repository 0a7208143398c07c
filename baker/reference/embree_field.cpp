#include "reference/embree_field.hpp"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "field/triangulation.hpp"

namespace hfbake::reference {
namespace {

void check_device(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) +
                             ")");
}

// The sheet: nx x ny vertices with vertex (i, j) at (i sx, j sy, height(i, j)).
template <class HeightAt>
RTCGeometry make_sheet(RTCDevice device, GeometryKind kind, int nx, int ny, double sx, double sy,
                       HeightAt height) {
  // The texel centres, row-major: the vertices of every geometry kind.
  auto set_vertices = [&](RTCGeometry g) {
    float* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), std::size_t(nx) * ny));
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        float* p = v + 3 * (std::size_t(j) * nx + i);
        p[0] = float(i * sx), p[1] = float(j * sy), p[2] = height(i, j);
      }
  };
  if (kind == GeometryKind::grid) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_GRID);
    set_vertices(g);
    // Grids of at most 1024 x 1024 quads sharing border vertices (Embree allows up to 32767 per side).
    constexpr int kBlock = 1024;
    const int bx = (nx - 2) / kBlock + 1, by = (ny - 2) / kBlock + 1;
    RTCGrid* grids = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID, sizeof(RTCGrid), std::size_t(bx) * by));
    for (int gy = 0; gy < by; ++gy)
      for (int gx = 0; gx < bx; ++gx) {
        RTCGrid& grid = grids[std::size_t(gy) * bx + gx];
        const int i0 = gx * kBlock, j0 = gy * kBlock;
        grid.startVertexID = unsigned(std::size_t(j0) * nx + i0);
        grid.stride = unsigned(nx);
        grid.width = (unsigned short)(std::min(kBlock, nx - 1 - i0) + 1);
        grid.height = (unsigned short)(std::min(kBlock, ny - 1 - j0) + 1);
      }
    rtcCommitGeometry(g);
    return g;
  }
  if (kind == GeometryKind::quads) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_QUAD);
    set_vertices(g);
    const std::size_t quads = std::size_t(nx - 1) * (ny - 1);
    unsigned* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), quads));
    std::size_t t = 0;
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        // v0 v1 v2 v3 = (i, j) (i+1, j) (i+1, j+1) (i, j+1): Embree splits it along v1-v3, the field's split.
        const unsigned v00 = unsigned(j * nx + i);
        idx[t++] = v00, idx[t++] = v00 + 1, idx[t++] = v00 + unsigned(nx) + 1, idx[t++] = v00 + unsigned(nx);
      }
    rtcCommitGeometry(g);
    return g;
  }
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  set_vertices(g);
  const std::size_t quads = std::size_t(nx - 1) * (ny - 1);
  unsigned* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
      g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 2 * quads));
  std::size_t t = 0;  // index of the next index
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      // The field's split (field/triangulation.hpp), like Embree's quads (v0 v1 v3) and (v2 v3 v1).
      const unsigned v00 = unsigned(j * nx + i);
      for (const auto& facet : kFacetCorner) {
        for (const auto& [di, dj] : facet) idx[t++] = v00 + unsigned(dj * nx + di);
      }
    }
  rtcCommitGeometry(g);
  return g;
}

// Walls from the boundary polyline (closed, counter-clockwise or not) down to z_bottom, plus a bottom cap.
// As quads (a wall quad is the two wall triangles, a cap triangle a quad with its last vertex repeated) when
// the sheet is made of quads: one primitive type, so a ray traverses one BVH instead of two.
RTCGeometry make_skirt(RTCDevice device, const std::vector<std::array<float, 3>>& ring, float z_bottom,
                       bool quads) {
  const std::size_t n = ring.size();
  RTCGeometry g = rtcNewGeometry(device, quads ? RTC_GEOMETRY_TYPE_QUAD : RTC_GEOMETRY_TYPE_TRIANGLE);
  float* v = static_cast<float*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 2 * n + 1));
  float cx = 0, cy = 0;
  for (std::size_t k = 0; k < n; ++k) {
    v[6 * k] = ring[k][0], v[6 * k + 1] = ring[k][1], v[6 * k + 2] = ring[k][2];
    v[6 * k + 3] = ring[k][0], v[6 * k + 4] = ring[k][1], v[6 * k + 5] = z_bottom;
    cx += ring[k][0] / float(n), cy += ring[k][1] / float(n);
  }
  v[6 * n] = cx, v[6 * n + 1] = cy, v[6 * n + 2] = z_bottom;  // cap center (the footprint is convex)
  if (quads) {
    unsigned* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), 2 * n));
    for (std::size_t k = 0; k < n; ++k) {
      const unsigned a = unsigned(2 * k), b = unsigned(2 * ((k + 1) % n));
      unsigned* q = idx + 8 * k;
      q[0] = a, q[1] = b, q[2] = b + 1, q[3] = a + 1;                              // wall: (a b a') (b' a' b)
      q[4] = a + 1, q[5] = b + 1, q[6] = unsigned(2 * n), q[7] = unsigned(2 * n);  // bottom cap fan
    }
  } else {
    unsigned* idx = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 3 * n));
    for (std::size_t k = 0; k < n; ++k) {
      const unsigned a = unsigned(2 * k), b = unsigned(2 * ((k + 1) % n));
      unsigned* t = idx + 9 * k;
      t[0] = a, t[1] = b, t[2] = a + 1;                    // wall
      t[3] = b, t[4] = b + 1, t[5] = a + 1;                // wall
      t[6] = a + 1, t[7] = b + 1, t[8] = unsigned(2 * n);  // bottom cap fan
    }
  }
  rtcCommitGeometry(g);
  return g;
}

}  // namespace

GeometryKind geometry_kind(const std::string& name) {
  return name == "grid"        ? GeometryKind::grid
         : name == "triangles" ? GeometryKind::triangles
                               : GeometryKind::quads;
}
const char* geometry_name(GeometryKind kind) {
  return kind == GeometryKind::grid ? "grid" : kind == GeometryKind::triangles ? "triangles" : "quads";
}
double embree_bytes_per_texel(GeometryKind kind) {
  return kind == GeometryKind::grid ? 36 : kind == GeometryKind::triangles ? 212 : 120;
}
double embree_fixed_bytes(GeometryKind kind) {
  return (kind == GeometryKind::grid ? 16 : kind == GeometryKind::triangles ? 5 : 8) * double(1 << 20);
}

EmbreeField::EmbreeField(const HeightField& f, GeometryKind kind, int repeat_tiles) {
  if (f.width < 2 || f.height < 2)
    throw std::invalid_argument("the reference needs a field of at least 2x2 texels");
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw std::runtime_error("embree: cannot create a device");
  const double ts = std::min(f.dx(), f.dy()), sx = f.dx(), sy = f.dy();
  const auto [zmin_it, zmax_it] = std::minmax_element(f.z.begin(), f.z.end());
  const double zmin = *zmin_it, zmax = *zmax_it;
  z_bottom_ = zmin - (zmax - zmin) - ts;
  const bool repeat = f.wrap == Wrap::repeat;
  const int T = repeat ? std::max(1, repeat_tiles) : 0;

  scene_ = rtcNewScene(device_);
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);

  std::vector<std::array<float, 3>> ring;  // boundary of the whole surface, for the skirt
  if (!repeat) {
    RTCGeometry sheet = make_sheet(device_, kind, f.width, f.height, sx, sy,
                                   [&](int i, int j) { return f.z[f.index(i, j)]; });
    rtcAttachGeometry(scene_, sheet);
    rtcReleaseGeometry(sheet);
    const int W = f.width, H = f.height;
    for (int i = 0; i < W - 1; ++i) ring.push_back({float(i * sx), 0.0f, f.z[f.index(i, 0)]});
    for (int j = 0; j < H - 1; ++j)
      ring.push_back({float((W - 1) * sx), float(j * sy), f.z[f.index(W - 1, j)]});
    for (int i = W - 1; i > 0; --i)
      ring.push_back({float(i * sx), float((H - 1) * sy), f.z[f.index(i, H - 1)]});
    for (int j = H - 1; j > 0; --j) ring.push_back({0.0f, float(j * sy), f.z[f.index(0, j)]});
  } else {
    tile_ = rtcNewScene(device_);
    rtcSetSceneFlags(tile_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(tile_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry sheet = make_sheet(device_, kind, f.width + 1, f.height + 1, sx, sy,
                                   [&](int i, int j) { return f.at(i, j); });
    rtcAttachGeometry(tile_, sheet);
    rtcReleaseGeometry(sheet);
    rtcCommitScene(tile_);
    const double tw = f.width * sx, th = f.height * sy;
    for (int ty = -T; ty <= T; ++ty)
      for (int tx = -T; tx <= T; ++tx) {
        RTCGeometry inst = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(inst, tile_);
        const float xfm[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, float(tx * tw), float(ty * th), 0};
        rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
        rtcCommitGeometry(inst);
        rtcAttachGeometry(scene_, inst);
        rtcReleaseGeometry(inst);
      }
    // The block spans tile vertices [-T W, (T+1) W] x [-T H, (T+1) H].
    const int i0 = -T * f.width, i1 = (T + 1) * f.width, j0 = -T * f.height, j1 = (T + 1) * f.height;
    for (int i = i0; i < i1; ++i) ring.push_back({float(i * sx), float(j0 * sy), f.at(i, j0)});
    for (int j = j0; j < j1; ++j) ring.push_back({float(i1 * sx), float(j * sy), f.at(i1, j)});
    for (int i = i1; i > i0; --i) ring.push_back({float(i * sx), float(j1 * sy), f.at(i, j1)});
    for (int j = j1; j > j0; --j) ring.push_back({float(i0 * sx), float(j * sy), f.at(i0, j)});
  }
  RTCGeometry skirt = make_skirt(device_, ring, float(z_bottom_), kind == GeometryKind::quads && !repeat);
  rtcAttachGeometry(scene_, skirt);
  rtcReleaseGeometry(skirt);
  rtcCommitScene(scene_);
  check_device(device_, "building the height-field scene");

  double max_coord = std::max(std::abs(zmin), std::abs(zmax));
  max_coord = std::max(max_coord, (T + 1) * std::max(f.width * sx, f.height * sy));
  float_floor_ = 16 * double(FLT_EPSILON) * max_coord;
  epsilon_ = std::max(1e-3 * ts, float_floor_);
}

EmbreeField::~EmbreeField() {
  if (scene_) rtcReleaseScene(scene_);
  if (tile_) rtcReleaseScene(tile_);
  if (device_) rtcReleaseDevice(device_);
}

}  // namespace hfbake::reference
