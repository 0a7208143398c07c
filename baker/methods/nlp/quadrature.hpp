// Gauss-Legendre quadrature on an interval: the start-up integrals of NLP/SH (SH product tensor, wedge
// matrices, environment projection).
#pragma once

#include <vector>

namespace hfbake {

struct QuadratureRule {
  std::vector<double> x, w;  // nodes and weights
};

// n-point Gauss-Legendre rule on [a, b] (exact for polynomials of degree <= 2n - 1).
QuadratureRule gauss_legendre(int n, double a = -1.0, double b = 1.0);

}  // namespace hfbake
