#include "methods/nlp/quadrature.hpp"

#include <cmath>

#include "core/vec.hpp"

namespace hfbake {

// Nodes are the roots of P_n, found by Newton's method from the Chebyshev-like initial guesses.
QuadratureRule gauss_legendre(int n, double a, double b) {
  QuadratureRule r;
  r.x.resize(n);
  r.w.resize(n);
  const double half = 0.5 * (b - a), mid = 0.5 * (b + a);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(kPi * (i + 0.75) / (n + 0.5)), dp = 1;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    {
      // recompute the derivative at the converged root
      double p0 = 1, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1);
    }
    r.x[i] = mid - half * z;
    r.w[i] = half * 2 / ((1 - z * z) * dp * dp);
  }
  return r;
}

}  // namespace hfbake
