// The azimuths every method's K directions use (contract: phi_k = 2 pi k / K, measured in the xy-plane
// from +x towards +y; the horizon layer's channel k is direction k).
#pragma once

#include <cmath>
#include <vector>

#include "core/vec.hpp"

namespace hfbake {

inline double azimuth(int k, int K) {
  return 2 * kPi * k / K;
}

// cos and sin of every azimuth phi_k, k = 0..K-1, rounded to T.
template <class T>
void azimuth_table(int K, std::vector<T>& cos_phi, std::vector<T>& sin_phi) {
  cos_phi.resize(K);
  sin_phi.resize(K);
  for (int k = 0; k < K; ++k) {
    cos_phi[k] = T(std::cos(azimuth(k, K)));
    sin_phi[k] = T(std::sin(azimuth(k, K)));
  }
}

}  // namespace hfbake
