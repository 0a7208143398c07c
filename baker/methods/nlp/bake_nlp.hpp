// NLP/SH multiresolution global illumination: Nowrouzezahrai & Snyder, "Fast Global Illumination
// on Dynamic Height Fields" (EGSR 2009, NS09), offline. Per texel and azimuth a horizon march over a B-spline
// height pyramid gives the visibility and indirect radiance along that azimuth in the normalized Legendre
// basis; wedge matrices turn the m azimuths into order-4 SH visibility V and indirect radiance U; shading is
// the SH product of the environment with V (direct) and U (indirect), dotted with the clamped cosine about
// the texel normal. Directional lights use the restricted-extent visibility of NS09 §6.
#pragma once

#include <string>
#include <vector>

#include "core/layers.hpp"
#include "core/run_control.hpp"
#include "field/scene.hpp"
#include "job/params.hpp"
#include "methods/method_table.hpp"
#include "methods/nlp/wedge_matrices.hpp"

namespace hfbake {

struct NlpOptions {
  int directions = 32;            // m azimuths (NS09 default 32)
  int levels_per_octave = 4;      // k_v = k_u
  int level_offset = 4;           // o_v (visibility; NS09: 2)
  int radiance_level_offset = 4;  // o_u (indirect radiance; NS09: 2)
  nlp::AzimuthInterpolation interpolation = nlp::AzimuthInterpolation::linear;
  int light_level_offset = 4;       // o_v for directional lights' visibility (>= level_offset)
  bool light_horizon_knots = true;  // lights: max over the knot angles instead of the B-spline curve
  // Visibility V: the same choice (default the knots; NS09 Eq. 16's B-spline curve lowers sharp peaks).
  // The defaults below (knots, exact cosines, facet senders, near_spacing 0.5) are the most accurate
  // measured (docs/methods/nlp.md); NS09's behaviour is a preset in baker/methods/nlp/README.md.
  bool visibility_horizon_knots = true;
  int light_directions = 3;  // azimuths across a directional light's disk (NS09 §9: 3)
  int subsample = 1;         // 1, or 2: V and U on a 2x2-subsampled grid, shading at full resolution
  // The indirect layer: true = the casting-set segments integrated per azimuth with the exact cosine about
  // the texel normal; false = NS09 §7, U dotted with the order-3 clamped-cosine lobe (it over-weights grazing
  // radiance). subsample 2 always uses U. sh_irradiance is U's either way.
  bool exact_indirect_cosine = true;
  // The direct layer's environment light: true = per azimuth, the environment's radiance over that azimuth's
  // wedge integrated above the horizon with the exact cosine about the texel normal (as P1's lighting
  // tables); false = NS09, the SH product of the environment with V dotted with the order-3 clamped-cosine
  // lobe (order-4 truncation: -0.5 to -0.7 % on smooth ground). subsample 2 always uses the SH form;
  // sh_visibility, sh_irradiance and the facet senders' light are the SH form either way.
  bool exact_direct_cosine = true;
  // Senders of indirect light: true = every texel's two facets of the triangulated surface radiate the
  // light of their own normals, and the stretch a casting-set step reveals radiates from its middle, its
  // facet's light (with texel-centre senders a cliff face radiates the bright treads at its ends); false =
  // NS09, the radiance pyramid of texel-centre light read at the casting-set point.
  bool facet_senders = true;
  // > 0: the march samples the unfiltered field at most this many texels apart between knots and each knot
  // keeps the steepest sample (MarchSetup::near_spacing); 0 = NS09, one sample a knot.
  double near_spacing = 0.5;
  std::vector<std::string> layers = {"direct", "indirect", "total", "sh_visibility", "sh_irradiance"};
};

// Every layer nlp can write.
const std::vector<std::string>& nlp_layer_names();

// Reads the bake entry (schemas/methods/nlp.schema.json) with every check (file and pointer in errors;
// resolved values recorded).
NlpOptions read_nlp_options(Params& in);

LayerSet bake_nlp(const Scene& scene, const NlpOptions& options, const RunControl& rc);

// Bytes bake_nlp holds at its peak beyond its layers (the height and radiance pyramids from their exact
// sizes, direct and indirect, a bounce's exitant radiance): the method table's working_bytes.
double nlp_working_bytes(const FieldShape& field, const NlpOptions& options, int bounces);

// nlp's line of the method table.
MethodInfo nlp_method();

// The SH convention written into the EXR header (attribute "hfbake:sh_convention").
const char* sh_convention_text();

}  // namespace hfbake
