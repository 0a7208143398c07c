#include "job/far_field.hpp"

#include <algorithm>
#include <string>

namespace hfbake {

std::optional<FarFieldSpec> read_far_field(Params& in, const FieldShape& field, double below,
                                           const char* below_name) {
  const double shorter = std::min(field.dx(), field.dy());
  std::optional<FarFieldSpec> spec;
  in.object("far_field", [&](Params& far) {
    FarFieldSpec f;
    f.beyond = far.number("beyond", 100 * shorter, 1e-12, 1e12);
    f.cell = far.integer("cell", 8, 1, 4096);
    if (f.beyond < shorter)
      far.fail("beyond", "is shorter than one texel (" + std::to_string(shorter) + " world units)");
    if (!(f.beyond < below))
      far.fail("beyond", "(" + std::to_string(f.beyond) + " world units) is not less than " + below_name +
                             " (" + std::to_string(below) + "): the far field would never be walked");
    if (field.wrap == Wrap::repeat && (field.width % f.cell != 0 || field.height % f.cell != 0))
      far.fail("cell", "must divide the field's width and height (" + std::to_string(field.width) + " x " +
                           std::to_string(field.height) + ") on a repeat field");
    spec = f;
  });
  return spec;
}

std::optional<FarFieldSpec> read_field_wide_far_field(Params& in, const FieldShape& field) {
  std::optional<FarFieldSpec> spec = read_far_field(in, field);
  if (spec && field.wrap == Wrap::repeat)
    in.fail("far_field", "needs a clamp field: a repeating field has no casters beyond its own period");
  return spec;
}

}  // namespace hfbake
