// Reference horizons: the horizon of every texel in the K azimuths of docs/contract.md (phi_k = 2 pi k / K),
// found by casting rays against the Embree surface (embree_field.hpp), independently of any sweep.
//
// From a point of a height field, visibility along an azimuth is monotone in elevation: a ray that hits
// the terrain at horizontal distance r passes every lower ray of that azimuth over the same point, lower.
// So the horizon elevation is found by bisection on the elevation in [-pi/2, pi/2] with occlusion rays
// from the receiver (the texel centre lifted vertically by max(1e-5 texel, EmbreeField::float_floor()),
// less than the reference's other receivers, since a lift adds its fraction of a near caster's rise to the
// elevation): `iterations` halvings (40: below 3e-12 rad, far below float). The distance is that of the
// hit of the highest occluded ray: the world distance to the caster, as P1's horizon_distance. The skirt
// counts as terrain, so looking out over a border the horizon is the border's edge.
//
// With the Earth's curvature c (Scene::curvature: a caster at horizontal distance d is lowered by c d^2),
// lowering every caster by c d^2 is the same as raising the line of sight by c d^2 over the flat surface:
// the ray of elevation e is the parabola z0 + d tan e + c d^2, traced as a chain of straight chords whose
// vertices lie on it (CurvedRays). A chord of horizontal length L from d0 lies above the parabola by
// |c| (d - d0) (d0 + L - d) at d: at most its sagitta |c| L^2 / 4 = CurvedRays::sagitta, and at most
// |c| L (d - d0) <= |c| L d. So the chain sees a caster at distance d within min(sagitta / d, |c| L) radians
// of the curved ray's elevation: with 1 m texels on the Earth (c = 6.8e-8 per metre, L = 77 m), 5e-6 rad
// near the receiver and 1e-4 / d rad beyond. Visibility stays monotone in e (a higher parabola of one
// azimuth is higher at every d), so the bisection holds.
#pragma once

#include <limits>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/height_field.hpp"

namespace hfbake {

struct ReferenceHorizons {
  int K = 0;
  std::vector<float> sin_elevation;  // [texel * K + k]
  std::vector<float> distance;       // [texel * K + k], world units (empty unless asked for)
};

namespace reference {
class EmbreeField;
}

// One receiver's horizon along the azimuth (c, s) (a unit vector in the xy-plane): the elevation in radians
// after `iterations` halvings of [-pi/2, pi/2], and the distance to the hit of the highest occluded ray.
// max_horizontal (world units): only surface within that horizontal distance counts (the rays end there): the
// horizon within a search radius, as relief's. Straight down is occluded whatever the limit (the surface
// under the receiver).
struct TexelHorizon {
  double elevation = 0, distance = 0;
};
// The curved rays of a field with curvature c per world unit (c = 0: straight rays): chords of horizontal
// length step = 2 sqrt(sagitta / |c|), sagitta = 1e-4 of the shorter texel side, out to `reach` (the
// horizontal extent of the traced geometry, beyond which nothing is hit); above z_top (the field's highest
// point) a rising ray can hit nothing more.
struct CurvedRays {
  double curvature = 0, step = 0, reach = 0, z_top = 0, sagitta = 0;
};
CurvedRays curved_rays(const HeightField& field, double curvature);
TexelHorizon bisect_horizon(const reference::EmbreeField& geometry, const Vec3& receiver, double c, double s,
                            int iterations, double max_horizontal = std::numeric_limits<double>::infinity(),
                            const CurvedRays& curved = {});
// The lift of a horizon receiver above its texel centre: max(1e-5 texel, the geometry's float floor).
double horizon_receiver_lift(const HeightField& field, const reference::EmbreeField& geometry);
// Texel (i, j)'s horizon towards (c, s) from its centre lifted by `lift`: bisected (bisect_horizon), but on
// a clamp field's border looking along it. That ray runs in the plane of the mesh's outer edges, where
// Embree reports no hit, not even straight down; the surface it passes over is the border's polyline, whose
// steepest point (a vertex, or where the polyline reaches max_horizontal; less the curvature's drop) is the
// horizon, found exactly. max_horizontal as bisect_horizon's.
TexelHorizon texel_horizon(const HeightField& field, const reference::EmbreeField& geometry, int i, int j,
                           double lift, double c, double s, int iterations, const CurvedRays& curved = {},
                           double max_horizontal = std::numeric_limits<double>::infinity());

// Halvings of the elevation's range [-pi/2, pi/2] per texel and azimuth: pi / 2^32 (7e-10 rad). The
// elevation is resolved long before (Embree's rays are single precision); the last halvings decide which
// of two casters at nearly the same elevation the distance is of: on a rough 40^2 field at K = 12 the
// distances differ from the exact march's in 1.04 % of the texel-directions at 32 halvings, 0.98 % at 40
// and 2.0 % at 28 (ReferenceHorizons.AgreeWithTheExactMarchOnRoughTerrain).
inline constexpr int kHorizonBisections = 32;

// curvature: Scene::curvature (0: flat).
ReferenceHorizons trace_reference_horizons(const HeightField& field, int K, bool distance,
                                           const RunControl& rc, int iterations = kHorizonBisections,
                                           double curvature = 0);

// Adds "horizon" (and "horizon_distance") to a reference's layers when one of `methods` bakes it: K is that
// layer's channel count, the channel names are the method's. The first method's K wins: a method with
// another K is left out of the comparison (report.json lists it under not_compared). Nothing is added when
// no method bakes a horizon or the reference has the layer already.
void add_reference_horizons(const HeightField& field, const std::vector<const LayerSet*>& methods,
                            LayerSet& reference, const RunControl& rc, double curvature = 0);

}  // namespace hfbake
