// Linear RGB in double for the CPU reference (radiance, irradiance, albedo).
#pragma once

namespace luxel::reference {

struct Rgb {
  double r = 0, g = 0, b = 0;

  static Rgb gray(double v) { return {v, v, v}; }
  double operator[](int c) const { return c == 0 ? r : (c == 1 ? g : b); }
  Rgb& operator+=(const Rgb& o) {
    r += o.r;
    g += o.g;
    b += o.b;
    return *this;
  }
  // Rec. 709 luminance, the weights the engine's error estimate uses.
  double luminance() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
  bool is_black() const { return r == 0 && g == 0 && b == 0; }
};

inline Rgb operator*(const Rgb& a, const Rgb& b) {
  return {a.r * b.r, a.g * b.g, a.b * b.b};
}
inline Rgb operator*(const Rgb& a, double s) {
  return {a.r * s, a.g * s, a.b * s};
}
inline Rgb operator+(const Rgb& a, const Rgb& b) {
  return {a.r + b.r, a.g + b.g, a.b + b.b};
}

}  // namespace luxel::reference
