// Obscurance falloff rho(d): rho(0) = 1, non-increasing, rho(inf) = 0 (except "none": plain AO).
// Shared by the obscurance family and the reference, so both integrate the same function.
#pragma once

#include <cmath>
#include <string>

#include "job/params.hpp"

namespace hfbake {

enum class FalloffKind { none, step, linear, smooth, exponential, rational };

struct Falloff {
  FalloffKind kind = FalloffKind::none;
  double radius = 0;  // world units. none: unused (rho = 1 at any distance)

  // step: 1 for d < R. linear: 1 - d/R. smooth: (1 - d/R)^2 (quadratic, zero slope at R).
  // exponential: exp(-d/R) (R = 1/e distance, no cut-off). rational (P3): r / (r + d^2) with r = R^2
  // (R = half-value distance).
  double operator()(double d) const {
    const double t = radius > 0 ? d / radius : 0.0;
    switch (kind) {
      case FalloffKind::none:
        return 1.0;
      case FalloffKind::step:
        return t < 1.0 ? 1.0 : 0.0;
      case FalloffKind::linear:
        return t < 1.0 ? 1.0 - t : 0.0;
      case FalloffKind::smooth:
        return t < 1.0 ? (1.0 - t) * (1.0 - t) : 0.0;
      case FalloffKind::exponential:
        return std::exp(-t);
      case FalloffKind::rational:
        return 1.0 / (1.0 + t * t);
    }
    return 0.0;
  }
  // Distance beyond which rho is below `eps` (infinite for none): how far a method must look.
  double support(double eps = 1e-4) const {
    switch (kind) {
      case FalloffKind::none:
        return INFINITY;
      case FalloffKind::step:
      case FalloffKind::linear:
      case FalloffKind::smooth:
        return radius;
      case FalloffKind::exponential:
        return radius * -std::log(eps);
      case FalloffKind::rational:
        return radius * std::sqrt(1.0 / eps - 1.0);
    }
    return INFINITY;
  }
};

inline bool parse_falloff_kind(const std::string& s, FalloffKind& k) {
  static const char* names[] = {"none", "step", "linear", "smooth", "exponential", "rational"};
  for (int i = 0; i < 6; ++i)
    if (s == names[i]) {
      k = FalloffKind(i);
      return true;
    }
  return false;
}

inline const char* falloff_kind_name(FalloffKind k) {
  static const char* const names[] = {"none", "step", "linear", "smooth", "exponential", "rational"};
  return names[int(k)];
}

// The one rule for "falloff" and "radius", for the obscurance family and the reference alike: falloff
// defaults to "step" when a radius is given, else "none"; every falloff but none needs a radius (world
// units, positive and finite), and none refuses one (it has no effect). Recorded resolved.
inline Falloff read_falloff(Params& in) {
  Falloff f;
  const bool has_radius = in.has("radius");
  const std::string kind = in.choice("falloff", has_radius ? "step" : "none",
                                     {"none", "step", "linear", "smooth", "exponential", "rational"});
  parse_falloff_kind(kind, f.kind);
  if (has_radius) {
    f.radius = in.number_that(
        "radius", [](double r) { return r > 0 && r <= 1e9; },
        "must be a positive number up to 1e9 (world units)");
  }
  if (f.kind == FalloffKind::none && has_radius)
    in.fail("radius", "has no effect with falloff \"none\" (use \"step\" for AO limited to a radius)");
  if (f.kind != FalloffKind::none && !has_radius)
    in.fail("radius", "is required with a falloff other than \"none\" (world units)");
  return f;
}

}  // namespace hfbake
