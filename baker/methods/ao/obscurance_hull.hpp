// The obscurance hull of Line-Sweep Ambient Obscurance (P3, Timonen 2013, Algorithm 1), at the level of
// one sweep line: a sequence of samples (s, z) with s the world distance along the line (increasing in the
// sweep direction) and z the world height. Every sample is a receiver whose occluders are the samples
// before it on the line, and then becomes an occluder itself.
//
// Per receiver the value is P3 Eq. 1 for the single "largest occluder" h (vector receiver -> occluder in
// the slice, zenith +z, the fixed tangent of strategy 3):
//     occlusion(h) = Wt + max(0, W(sin e(h)) - Wt) * rho(|h|),    Wt = W(sin_t)
// with sin e(h) = h.z / |h| and W the elevation weight: W(x) = x (uniform: P3's HBAO estimator, the
// solid-angle measure of the slice below e) or W(x) = x |x| (cosine: the cosine-weighted slice measure
// sin^2 e of an upward normal, signed so that it stays strictly increasing below the horizontal; what the
// cosine-weighted obscurance of docs/contract.md converges to for rho = 1). With no occluder the value is Wt.
//
// The hull keeps the candidates: before a receiver reads the top of the stack, the top is popped while the
// second-to-last point casts more obscurance on the receiver AND is higher in elevation (P3 §3, Alg. 1;
// the elevation test stops popping at the receiver's global horizon). Amortised O(1) per sample: M pushes,
// at most M pops per line. The result is not always the exact largest occluder (P3 §3 "degenerate case"): a
// point popped for one receiver can be the largest visible occluder of a later one.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "methods/ao/falloff.hpp"

namespace hfbake {

enum class ObscuranceWeighting { cosine, uniform };

struct SlicePoint {
  double s = 0;  // world distance along the line
  double z = 0;  // world height
};

// The per-occluder value of P3 Eq. 1 (see the file comment). Plain data, cheap to copy.
struct OcclusionFunction {
  Falloff rho;
  double sin_t = -0.85;  // the fixed tangent (P3 strategy 3); must be in [-1, 0]
  ObscuranceWeighting weighting = ObscuranceWeighting::cosine;

  double weight(double sin_e) const {
    return weighting == ObscuranceWeighting::uniform ? sin_e : sin_e * std::fabs(sin_e);
  }
  double none() const { return weight(sin_t); }  // the value with no occluder
  // Occluder at vector (hs, hz) from the receiver, hs > 0.
  double operator()(double hs, double hz) const {
    const double d = std::sqrt(hs * hs + hz * hz);
    const double wt = none();
    const double w = weight(hz / d);
    return wt + (w > wt ? (w - wt) * rho(d) : 0.0);
  }
};

inline double sine_elevation(double hs, double hz) {
  return hz / std::sqrt(hs * hs + hz * hz);
}

// One line's hull. Reuse one object per thread (clear() keeps the capacity): no allocation per sample.
class ObscuranceHull {
 public:
  void reserve(std::size_t n) { stack_.reserve(n); }
  void clear() {
    stack_.clear();
    iterations_ = 0;
  }

  // The value for receiver p (does not push p). Pops what the hull rule discards.
  double receive(SlicePoint p, const OcclusionFunction& f) {
    std::size_t n = stack_.size();
    if (n == 0) return f.none();
    SlicePoint a = stack_[n - 1];
    double h1s = p.s - a.s, h1z = a.z - p.z;  // occluders lie behind: h1s > 0
    double o1 = f(h1s, h1z);
    while (n >= 2) {
      const SlicePoint b = stack_[n - 2];
      const double h2s = p.s - b.s, h2z = b.z - p.z;
      const double o2 = f(h2s, h2z);
      if (!(o1 < o2 && sine_elevation(h1s, h1z) < sine_elevation(h2s, h2z))) break;
      stack_.pop_back();
      ++iterations_;  // a loop test that pops
      --n;
      h1s = h2s, h1z = h2z, o1 = o2;
    }
    ++iterations_;  // the one loop test that ends without popping
    return o1;
  }
  // The value receive() would return for p, without popping (for receivers beside the line, e.g. the
  // texel centres a sample between two texels feeds; P3's pop rule walked on a copy of the stack top).
  // occluder (optional): the vector receiver -> the chosen occluder (s: distance back along the line, z:
  // height above the receiver); left untouched when the stack is empty (no occluder).
  double query(SlicePoint p, const OcclusionFunction& f, SlicePoint* occluder = nullptr) const {
    std::size_t n = stack_.size();
    if (n == 0) return f.none();
    double h1s = p.s - stack_[n - 1].s, h1z = stack_[n - 1].z - p.z;
    double o1 = f(h1s, h1z);
    while (n >= 2) {
      const SlicePoint b = stack_[n - 2];
      const double h2s = p.s - b.s, h2z = b.z - p.z;
      const double o2 = f(h2s, h2z);
      if (!(o1 < o2 && sine_elevation(h1s, h1z) < sine_elevation(h2s, h2z))) break;
      --n;
      h1s = h2s, h1z = h2z, o1 = o2;
    }
    if (occluder) *occluder = {h1s, h1z};
    return o1;
  }
  void push(SlicePoint p) { stack_.push_back(p); }
  std::size_t size() const { return stack_.size(); }
  // Loop tests since clear(): between M and 2M for a line of M receivers (P3 §3).
  std::size_t iterations() const { return iterations_; }

 private:
  std::vector<SlicePoint> stack_;
  std::size_t iterations_ = 0;
};

// The whole line: out[i] = value for receiver i, for i >= first_receiver; samples before first_receiver
// only become occluders (warm-up for wrapped fields or an apron). out.size() >= pts.size().
void sweep_obscurance_line(const SlicePoint* pts, std::size_t count, std::size_t first_receiver,
                           const OcclusionFunction& f, ObscuranceHull& hull, double* out);

// Brute force over the same samples (the P3 Fig. 7 reference): per receiver, march back over every
// earlier sample and take the largest occlusion(). visible_only: only samples at or above the running
// maximum elevation seen from the receiver count (the reading with the elevation condition); otherwise
// every earlier sample counts ("were it the only occluder"). O(M^2): tests and measurements only.
void brute_force_obscurance_line(const SlicePoint* pts, std::size_t count, const OcclusionFunction& f,
                                 bool visible_only, double* out);

}  // namespace hfbake
