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
TexelHorizon bisect_horizon(const reference::EmbreeField& geometry, const Vec3& receiver, double c, double s,
                            int iterations, double max_horizontal = std::numeric_limits<double>::infinity());
// The lift of a horizon receiver above its texel centre: max(1e-5 texel, the geometry's float floor).
double horizon_receiver_lift(const HeightField& field, const reference::EmbreeField& geometry);

ReferenceHorizons trace_reference_horizons(const HeightField& field, int K, bool distance,
                                           const RunControl& rc, int iterations = 40);

// Adds "horizon" (and "horizon_distance") to a reference's layers when one of `methods` bakes it: K is that
// layer's channel count, the channel names are the method's. The first method's K wins: a method with
// another K is left out of the comparison (report.json lists it under not_compared). Nothing is added when
// no method bakes a horizon or the reference has the layer already.
void add_reference_horizons(const HeightField& field, const std::vector<const LayerSet*>& methods,
                            LayerSet& reference, const RunControl& rc);

}  // namespace hfbake
