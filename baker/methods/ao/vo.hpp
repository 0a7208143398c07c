// vo: adaptively layered statistical volumetric obscurance (Hendrickx 2015, "ALSVO"),
// evaluated in tangent space on a height field.
//
// Footprint: the (2b + 1)^2 texels around the receiver (b = radius / texel_size, rounded), clipped at clamped
// borders (the counts renormalise), wrapped on repeating fields. The field's texels are split into height
// layers adaptively: a texel goes to the upper child of its layer when it lies above its layer's mean over
// its own footprint (the thesis' §4.4), `levels` times (4 leaf layers = 2 splits, the paper's choice). Per
// leaf layer a summed-area table of (x, y, z, count) gives the layer's mean position m_i in the receiver's
// footprint; its offset along the normal, delta_i = (m_i - p).n, goes through the response f (0 below the
// tangent plane, a ramp to 1 at the box height h, a linear fade to 0 over F above it: the thesis' shader,
// App. A.2); the occlusion is sum_i f(delta_i) n_i / sum_i n_i and the output obscurance is 1 - occlusion.
//
// What it converges to: with many layers each layer is flat, and the estimate becomes the box
// volumetric obscurance (1/N) sum_{texels j in the footprint} f((p_j - p).n): with F large, the fraction of a
// tangent-space box (footprint x height h above the tangent plane) that the terrain fills. It has no
// visibility and no cosine: it is NOT the hemisphere obscurance of the other methods (tests quantify the
// gap).
#pragma once

#include <vector>

#include "core/run_control.hpp"
#include "core/vec.hpp"
#include "field/height_field.hpp"
#include "job/params.hpp"

namespace hfbake {

struct VoSettings {
  double radius = 8;      // footprint half-width b, world units
  double box_height = 8;  // h, world units
  double fade = 8;        // F, world units
  int levels = 2;         // adaptive splits: 2^levels leaf layers
};

// The response f(delta) of a layer whose mean lies delta above the tangent plane.
double vo_response(double delta, double box_height, double fade);

// Volumetric obscurance of the whole field (occlusion in [0, 1] per texel, 1 - obscurance).
std::vector<float> vo_occlusion(const HeightField& field, const std::vector<Vec3f>& normals,
                                const VoSettings& s, const RunControl& rc);

// The brute-force box volumetric obscurance at one texel, (1/N) sum_j f((p_j - p).n): what vo converges to.
double vo_brute_force(const HeightField& field, Vec3 normal, int i, int j, const VoSettings& s);

// Reads and checks a vo bake entry (schemas/methods/vo.schema.json).
VoSettings read_vo_settings(Params& in, const FieldShape& field);

}  // namespace hfbake
