// How environment images map to world directions. Pure geometry (no image I/O): the loaders in baker/io
// use it, and the tests pin it against OpenEXR's own environment-map functions.
//
// Input images follow OpenEXR's environment-map conventions (ImfEnvmap.h), whose frame is y-up:
// lat-long longitude +pi at the left edge to -pi at the right, latitude +pi/2 at the top row; longitude 0
// is +z_exr, longitude +pi/2 is +x_exr; cube faces in the order +x, -x, +y, -y, +z, -z.
// hfbake maps that frame to its z-up world by the rotation (a cyclic permutation, right-handed)
//
//     world (x, y, z) = exr (z, x, y)        i.e. +z_exr -> +x, +x_exr -> +y, +y_exr (image up) -> +z
//
// so world azimuth phi (from +x towards +y) equals OpenEXR's longitude. In a lat-long image:
//
//     column:   left edge      1/4        center      3/4       right edge
//     phi:        180 deg     90 deg      0 deg     -90 deg      -180 deg
//     faces:        -x          +y          +x         -y           -x
//     row 0 (top) = zenith (+z), bottom row = nadir (-z), the middle row boundary = the horizon.
//
// This is also Blender's equirectangular convention for a z-up world. Pixels are areas that tile the
// sphere edge to edge (as OpenImageIO's texture system and common HDRI tools assume): column c covers
// phi in (pi - 2 pi (c + 1) / W, pi - 2 pi c / W]; OpenEXR's helper functions instead put the outermost
// pixel *centers* on the poles and the seam, a half-pixel difference.
#pragma once

#include <array>

#include "core/vec.hpp"

namespace hfbake {

inline Vec3 world_from_openexr(Vec3 d) {
  return {d.z, d.x, d.y};
}
inline Vec3 openexr_from_world(Vec3 d) {
  return {d.y, d.z, d.x};
}

// Rotates a direction about +z by `radians` (counter-clockwise seen from above).
Vec3 rotate_about_z(Vec3 d, double radians);

// Lat-long image of width w, height h: continuous pixel coordinates (u to the right, v down, in pixels;
// pixel (c, r) covers [c, c + 1) x [r, r + 1)) of a world direction, and back.
void latlong_pixel_of(Vec3 world_dir, int w, int h, double& u, double& v);
Vec3 latlong_direction_of(double u, double v, int w, int h);

// A square face image: the world directions of its center, of image right (growing column) and of image
// up (shrinking row). Pixel (x, y) of an n x n face looks along
//     normalize(center + a * right + b * up),  a = 2 (x + 0.5) / n - 1,  b = 1 - 2 (y + 0.5) / n.
struct FaceFrame {
  Vec3 center, right, up;
};

// The six faces of an OpenEXR cube map (order +x, -x, +y, -y, +z, -z in OpenEXR's frame), in world
// coordinates:
//     face   OpenEXR   looks at (world)   image right   image up
//      0       +x           +y               +x           +z
//      1       -x           -y               -x           +z
//      2       +y           +z (zenith)      +y           +x
//      3       -y           -z (nadir)       +y           -x
//      4       +z           +x               -y           +z
//      5       -z           -x               +y           +z
FaceFrame openexr_cube_face(int face);

// Cube crosses (one image). The center of the cross ("front") looks at world +x, like the center of a
// lat-long; faces are seen from inside, image up = world up:
//
//   horizontal (4:3)              vertical (3:4)
//        [top]                        [top]
//  [left][front][right][back]   [left][front][right]
//        [bottom]                     [bottom]
//                                     [back]  (stored upside down)
//
//   front +x, left +y, right -y, back -x, top +z, bottom -z. The side faces are OpenEXR's +x, +z, -x, -z
//   faces as they are; top and bottom are OpenEXR's +y and -y faces turned 180 degrees.
enum class CrossLayout { horizontal, vertical };
struct CrossFace {
  int col = 0, row = 0;  // cell in the cross grid (face size units)
  FaceFrame frame;
};
std::array<CrossFace, 6> cross_faces(CrossLayout layout);

// Pixel coordinates (continuous, x right, y down, pixel (x, y) covers [x, x + 1) x [y, y + 1)) in an
// n x n face of a world direction d with dot(d, center) > 0.
void face_pixel_of(const FaceFrame& f, Vec3 d, int n, double& x, double& y);

}  // namespace hfbake
