#include "methods/nlp/nlp_basis.hpp"

namespace hfbake::nlp {

double basis(int l, double z) {
  double p0 = 1, p1 = z;
  if (l == 0) return std::sqrt(0.5);
  for (int k = 2; k <= l; ++k) {
    const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  return std::sqrt((2 * l + 1) / 2.0) * p1;
}

}  // namespace hfbake::nlp
