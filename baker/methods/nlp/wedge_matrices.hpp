// From NLP elevation functions at m azimuths to a spherical function in SH (NS09 §6 and Appendix A).
//
// Within the azimuthal wedge between samples j and j + 1 (width dphi, canonically starting at phi = 0) the
// elevation function is an azimuthal blend of the samples' NLP vectors: linear (I_lin, Eq. 24) of samples
// j, j+1, or uniform cubic B-spline (I_bspl) of samples j-1..j+2. The SH projection of the wedge is a
// matrix acting on the stacked NLP vectors: M_lin (16 x 8) and M_bspl (16 x 32), here integrated by
// Gauss-Legendre quadrature (32 nodes in theta, 16 in phi; the integrands are smooth, the result is exact
// to rounding). Eq. 21's sum of z-rotated wedges is linear too, so hfbake folds it into one 16 x 4 matrix
// per azimuth sample: V = sum_j A_j v_j.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace hfbake::nlp {

enum class AzimuthInterpolation { linear, bspline };

bool parse_azimuth_interpolation(const std::string& name, AzimuthInterpolation& out);

// Taps per wedge: 2 (linear) or 4 (B-spline).
int wedge_taps(AzimuthInterpolation interp);

// Weight of tap b (0-based, see above) at fractional position alpha in [0, 1] within the wedge.
double wedge_weight(AzimuthInterpolation interp, int b, double alpha);

// The wedge matrix, row-major 16 x (4 * taps): column b * 4 + c multiplies coefficient c of tap b.
std::vector<double> wedge_matrix(AzimuthInterpolation interp, double dphi);

// Per-sample matrices for m samples at phi_j = 2 pi j / m covering the full circle (m wedges):
// A_j row-major 16 x 4, so that V = sum_j A_j v_j.
std::vector<std::array<float, 64>> sample_matrices(AzimuthInterpolation interp, int m);

}  // namespace hfbake::nlp
