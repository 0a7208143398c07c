// Small fixed-size vector types shared by every module (plain data, no dependencies).
#pragma once

#include <cmath>

namespace hfbake {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  friend Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
  friend Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
  friend Vec3 operator*(Vec3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
  friend Vec3 operator*(double s, Vec3 a) { return {a.x * s, a.y * s, a.z * s}; }
  friend Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
  Vec3& operator+=(Vec3 b) {
    x += b.x, y += b.y, z += b.z;
    return *this;
  }
};

inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length(Vec3 a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(Vec3 a) {
  const double l = length(a);
  return l > 0 ? a * (1.0 / l) : Vec3{0, 0, 1};
}

// Single-precision normal as stored per texel (12 bytes).
struct Vec3f {
  float x = 0, y = 0, z = 1;
  Vec3 d() const { return {x, y, z}; }
  static Vec3f from(Vec3 v) { return {float(v.x), float(v.y), float(v.z)}; }
};

// Linear RGB radiance / irradiance / albedo.
struct Rgb {
  float r = 0, g = 0, b = 0;
  friend Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
  friend Rgb operator-(Rgb a, Rgb b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
  friend Rgb operator*(Rgb a, Rgb b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
  friend Rgb operator*(Rgb a, float s) { return {a.r * s, a.g * s, a.b * s}; }
  friend Rgb operator*(float s, Rgb a) { return {a.r * s, a.g * s, a.b * s}; }
  Rgb& operator+=(Rgb o) {
    r += o.r, g += o.g, b += o.b;
    return *this;
  }
  float luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }  // Rec.709 / sRGB primaries
};

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kHalfPi = kPi / 2;

// floor(x) as an int for |x| < 2^31 without a libm call (baseline x86-64 has no rounding instruction).
inline int floor_int(double x) {
  const int i = int(x);
  return x < double(i) ? i - 1 : i;
}

}  // namespace hfbake
